"""Figures a student can hand in, on long thin maps and real course maps: legends off the
data, no label on another, the path visible on red blocks, the Tello top view in 2D;
and where ``animate`` and ``view`` write."""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pytest
from figurecheck import (
    DrawCounter,
    assert_labels_apart,
    assert_legends_outside,
    assert_outlined,
    draw,
)
from matplotlib import rc_context
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.image import imread
from matplotlib.patches import Rectangle
from mpl_toolkits.mplot3d import Axes3D

from quadnav.cli.main import main
from quadnav.hardware.bridge.flight_plan import plan_flight
from quadnav.hardware.bridge.track_figure import track_figure
from quadnav.mission import MissionSettings, fly_mission
from quadnav.planning import PlannerSettings, get_planner, make_problem
from quadnav.report.html_report import png_bytes
from quadnav.report.run_writer import write_run
from quadnav.runs import read_run
from quadnav.trajectory.generate import make_trajectory
from quadnav.viz.figures import save_figure
from quadnav.viz.flight_figures import flight_3d_figure
from quadnav.viz.map3d import MIN_SIDE, world_figure
from quadnav.viz.plan_figure import plan_figure
from quadnav.viz.style import PATH_COLOR, outlined
from quadnav.viz.trajectory_figures import states_figure, trajectory_3d_figure
from quadnav.world import World, load_world

RED = [[1.0, 0.0, 0.0]]
#: A corridor 30 m long, 2 m wide and high, with staggered red walls; and a shaft as tall.
LONG = World(boundary=[0, 0, 0, 30, 2, 2], name="corridor 30 x 2 x 2 m",
             blocks=[[5, 0, 0, 5.5, 1.3, 2], [12, 0.7, 0, 12.5, 2, 2]], colors=RED * 2)
TALL = World(boundary=[0, 0, 0, 2, 2, 20], name="shaft 2 x 2 x 20 m",
             blocks=[[0, 0, 5, 1.3, 2, 5.5], [0.7, 0, 10, 2, 2, 10.5]], colors=RED * 2)
FLAT = World(boundary=[0, 0, 0, 40, 40, 1.5], name="hall 40 x 40 x 1.5 m",
             blocks=[[10, 0, 0, 11, 30, 1.5]], colors=RED)
QUERIES = {"long": (LONG, (1, 1, 1), (29, 1, 1)), "tall": (TALL, (1, 1, 1), (1, 1, 19))}
COURSE_MAPS = ["rbe595/map1.txt", "rbe595/p2b_map1.txt", "rbe595/map4.txt"]


def quick_plan(world: World, start, goal):
    """An RRT* plan of a few thousand samples (not refined), and its problem."""
    problem = make_problem(world, start, goal, 0.2)
    return problem, get_planner("rrtstar")(problem, PlannerSettings(seed=0, max_iterations=3000),
                                           None)


@pytest.fixture(scope="module", params=sorted(QUERIES))
def planned(request):
    world, start, goal = QUERIES[request.param]
    problem, result = quick_plan(world, start, goal)
    assert result.solved
    return problem, result


@pytest.mark.parametrize("world", [LONG, TALL, FLAT], ids=lambda world: world.name)
def test_map_figure_of_a_long_thin_map_has_legend_outside_and_labels_apart(world):
    fig = world_figure(world)
    assert_legends_outside(fig)
    assert_labels_apart(fig)
    (ax,) = fig.axes
    aspect = np.asarray(ax.get_box_aspect())
    extent = world.extent
    # Only a side shorter than MIN_SIDE of the longest is drawn longer, and the legend says so.
    assert np.allclose(aspect / aspect.max(), np.maximum(extent, MIN_SIDE * extent.max())
                       / extent.max())
    note = fig.legends[0].get_texts()[-1].get_text()
    assert note.startswith("not to scale: ") and " stretched " in note


def test_map_figures_of_course_maps_have_legend_outside_and_labels_apart(shared_maps):
    for name in COURSE_MAPS:
        fig = world_figure(load_world(shared_maps / name))
        assert_legends_outside(fig)
        assert_labels_apart(fig)
        texts = [text.get_text() for text in fig.legends[0].get_texts()]
        assert not any(text.startswith("not to scale") for text in texts) or name.endswith(
            "map4.txt")  # 45 x 35 x 6 m: the height is stretched


def test_plan_figure_keeps_the_path_visible_and_the_legend_off_it(planned):
    problem, result = planned
    fig = plan_figure(problem, result)
    assert_legends_outside(fig)
    assert_labels_apart(fig)
    (path,) = [line for line in fig.axes[0].get_lines() if line.get_label().startswith("path")]
    assert path.get_color() == PATH_COLOR
    assert_outlined(path)


def test_trajectory_figures_have_legends_outside():
    problem, result = quick_plan(*QUERIES["long"])
    trajectory = make_trajectory(result.path)
    for fig in (trajectory_3d_figure(problem.world, trajectory, result.path),
                states_figure(trajectory, 1.0, 1.5)):
        assert_legends_outside(fig)
        assert_labels_apart(fig)


def test_a_finished_figure_is_drawn_once_when_saved(tmp_path, monkeypatch):
    """A 3D figure is laid out in rounds (its box zoomed to fit, crowded ticks thinned)
    and a 2D one in one, without drawing: saving it to a file or into a page draws it
    once."""
    counter = DrawCounter(monkeypatch)
    save_figure(world_figure(LONG), tmp_path / "long.png")
    png_bytes(world_figure(TALL))
    trajectory = make_trajectory(np.array([[1.0, 1.0, 1.0], [29.0, 1.0, 1.0]]))
    save_figure(states_figure(trajectory, 1.0, 1.5), tmp_path / "states.png")
    with rc_context({"figure.constrained_layout.use": True}):  # as a user's matplotlibrc may
        png_bytes(world_figure(FLAT))
    assert counter.of_figures() == [1, 1, 1, 1]


def test_an_opaque_figure_is_written_as_an_rgb_png_of_its_pixels(tmp_path):
    """A figure with an opaque face (every quadnav figure) is saved as RGB, a quarter fewer
    bytes to compress than savefig's RGBA, with the same pixels; one with a see-through
    face keeps its alpha; a figure made without a canvas (as the batch pages make theirs)
    is drawn too."""
    opaque, clear, plain = world_figure(TALL), world_figure(TALL), Figure(figsize=(3, 2))
    clear.patch.set_alpha(0.0)
    plain.subplots().plot([0, 1], [1, 0])
    for fig, name, colour_type in ((opaque, "opaque.png", 2), (clear, "clear.png", 6),
                                   (plain, "plain.png", 2)):
        save_figure(fig, tmp_path / name)
        data = (tmp_path / name).read_bytes()
        assert data[25] == colour_type  # IHDR's colour type: 2 RGB, 6 RGBA
        drawn = np.asarray(fig.canvas.buffer_rgba())
        written = imread(tmp_path / name)
        assert written.shape[:2] == drawn.shape[:2]
        assert np.array_equal(np.round(255 * written).astype(np.uint8),
                              drawn[..., :written.shape[2]])


def test_an_outlined_red_line_shows_on_a_red_block():
    """Across a red line drawn over a red block, the pixels run red, black, white, red,
    white, black, red: the line is told from the block by its edges."""
    fig = Figure(figsize=(2, 2), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0, 0, 1, 1), xlim=(0, 1), ylim=(0, 1))
    ax.set_axis_off()
    ax.add_patch(Rectangle((0, 0), 1, 1, color=PATH_COLOR))
    ax.plot([0, 1], [0.5, 0.5], color=PATH_COLOR, linewidth=2.2, path_effects=outlined(2.2))
    draw(fig)
    column = np.asarray(fig.canvas.buffer_rgba())[:, 100, :3].astype(int)
    kinds = ["red" if (r > 200 and g < 60) else "white" if min(r, g, b) > 200
             else "black" if max(r, g, b) < 60 else "mixed" for r, g, b in column]
    runs = [kind for k, kind in enumerate(kinds) if kind != "mixed"
            and (k == 0 or kind != kinds[k - 1])]
    assert [kind for k, kind in enumerate(runs) if k == 0 or kind != runs[k - 1]] == [
        "red", "black", "white", "red", "white", "black", "red"]


# --------------------------------------------------------------------------- the Tello
@pytest.fixture(scope="module")
def tello_plan(shared_maps_module):
    world = load_world(shared_maps_module / "rbe595/p2b_map1.txt")
    return plan_flight(world, (0.0, 0.0, 0.0), (-0.59, 6.81, 0.0), 0.2, 0.0,
                       planning=PlannerSettings(seed=0, max_iterations=2000))


@pytest.fixture(scope="module")
def shared_maps_module():
    from conftest import SHARED_MAPS

    if not SHARED_MAPS.is_dir():
        pytest.skip(f"public map corpus not found at {SHARED_MAPS}")
    return SHARED_MAPS


def test_tello_track_has_a_2d_top_view_and_the_legend_outside(tello_plan):
    mode = "rc"
    planned = tello_plan.planned_points(mode)
    flown = {"dead reckoning": planned + 0.05}
    fig = track_figure(tello_plan, mode, flown, "dry run")
    oblique, top = fig.axes
    assert isinstance(oblique, Axes3D) and (oblique.elev, oblique.azim) == (30, -60)
    assert not isinstance(top, Axes3D) and top.name == "rectilinear"
    assert top.get_aspect() == 1.0  # a metre is as long along x as along y
    assert top.get_title() == "top view" and top.get_xlabel() == "x (m)"
    lines = {line.get_label(): line for line in top.get_lines()}
    assert np.array_equal(lines[f"planned ({mode})"].get_xydata(), planned[:, :2])
    assert np.array_equal(lines["dead reckoning"].get_xydata(), flown["dead reckoning"][:, :2])
    assert_outlined(lines[f"planned ({mode})"])
    assert_legends_outside(fig)
    assert_labels_apart(fig)


# ------------------------------------------------------------- animate and view outputs
@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    """A run folder (no figures) of a short flight along the corridor."""
    folder = tmp_path_factory.mktemp("corridor")
    world = World(boundary=[0, 0, 0, 8, 2, 2], blocks=[[3, 0, 0, 3.5, 1.2, 2]], colors=RED,
                  start=[1, 1, 1], goal=[7, 1, 1], name="short corridor")
    settings = MissionSettings(planning=PlannerSettings(seed=0, max_iterations=400))
    mission = fly_mission(world, settings=settings)
    assert mission.success
    write_run(mission, folder, figures=False)
    return folder


def quadnav(*args) -> tuple[int, str, str]:
    """``quadnav ARGS`` in this process: exit code, stdout, stderr."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(arg) for arg in args])
    return code, out.getvalue(), err.getvalue()


def test_animate_writes_into_the_run_folder_by_default(run_folder, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = quadnav("animate", run_folder, "--max-frames", "2", "--quiet")
    assert code == 0, err
    gif = run_folder / "flight.gif"
    assert out.startswith(f"wrote {gif}: 2 frames")
    assert gif.read_bytes()[:6] == b"GIF89a"
    assert list(tmp_path.iterdir()) == []  # nothing in the current folder
    gif.unlink()


@pytest.mark.parametrize("name", ["page.txt", "page", "view.html.png"])
def test_view_output_must_end_in_html(run_folder, tmp_path, name):
    page = tmp_path / name
    code, out, err = quadnav("view", run_folder, "-o", page)
    assert (code, out) == (2, "")
    assert err == f"quadnav: error: {page}: expected a file name ending in .html\n"
    assert list(tmp_path.iterdir()) == []
    assert not (run_folder / "view.html").exists()


def test_view_output_in_a_missing_folder_is_refused_before_reading(tmp_path):
    page = tmp_path / "no" / "page.html"
    code, _, err = quadnav("view", tmp_path / "not-a-run", "-o", page)
    assert code == 2
    assert err == f"quadnav: error: {page}: folder {str(page.parent)!r} does not exist\n"


def test_flight_figure_of_a_corridor_has_a_top_view_below_and_the_legend_outside(run_folder):
    run = read_run(run_folder)
    fig = flight_3d_figure(run)
    oblique, top = fig.axes
    assert top.bbox.y1 < oblique.bbox.y0  # a map 4 times longer than wide: stacked
    assert top.get_aspect() == 1.0 and not isinstance(top, Axes3D)
    texts = [text.get_text() for text in fig.legends[0].get_texts()]
    assert texts[-1].startswith("flown (")  # 8 x 2 x 2 m is drawn to scale: no note
    assert_legends_outside(fig)
    assert_labels_apart(fig)
