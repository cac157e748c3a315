"""``quadnav blender``: a real run folder built into a real Blender scene by the command,
the .blend reopened with bpy and checked object by object, and both cameras' renders
checked as images. Tests that need Blender skip when bpy is not installed; the errors
are checked without it."""

from __future__ import annotations

import io
import math
import sys
from contextlib import redirect_stderr, redirect_stdout

import numpy as np
import pytest
from clitools import run
from matplotlib.image import imread

from quadnav.cli.main import main
from quadnav.mission import fly_mission
from quadnav.report.run_writer import write_run
from quadnav.runs import read_run
from quadnav.vehicle.quaternion import to_matrix
from quadnav.viz.blender_scene import BOUNDARY_ALPHA, MAX_TREE_EDGES, PATH_ALPHA, linear_rgb
from quadnav.world import load_world

SIZE = (480, 270)
FPS = 24


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    """A real small run: fly a 12 x 12 x 4 m forest and write its folder."""
    folder = tmp_path_factory.mktemp("run")
    mission = fly_mission(load_world("forest:size=12x12x4,seed=2"))
    assert mission.success
    write_run(mission, folder, figures=False)
    return folder


@pytest.fixture(scope="module")
def bpy():
    return pytest.importorskip("bpy", reason="Blender's bpy is not installed "
                                             "(pip install 'quadnav[blender]')")


@pytest.fixture(scope="module")
def written(bpy, run_folder, tmp_path_factory):
    """The scene and both renders written by the command (run in this process, to save
    the start-up of a second Python with Blender): the folder and what it printed."""
    out = tmp_path_factory.mktemp("blender")
    stdout, stderr = io.StringIO(), io.StringIO()
    with redirect_stdout(stdout), redirect_stderr(stderr):
        code = main(["blender", str(run_folder), "-o", str(out / "scene.blend"),
                     "--render", str(out / "oblique.png"), "--render", str(out / "top.png"),
                     "--size", f"{SIZE[0]}x{SIZE[1]}", "--fps", str(FPS)])
    assert (code, stderr.getvalue()) == (0, "")
    return out, stdout.getvalue()


@pytest.fixture(scope="module")
def opened(bpy, written):
    """The saved .blend opened again in this process."""
    bpy.ops.wm.open_mainfile(filepath=str(written[0] / "scene.blend"))
    return bpy.data


def material_rgba(obj) -> np.ndarray:
    return np.array(obj.material_slots[0].material.diffuse_color)


def test_summary_line(written, run_folder):
    out, stdout = written
    run_ = read_run(run_folder)
    frames = math.ceil(run_.flight.t[-1] * FPS) + 1
    lines = stdout.splitlines()
    assert len(lines) == 1
    assert f"({len(run_.world.blocks)} blocks, tree {MAX_TREE_EDGES:,} of " \
           f"{len(run_.tree_edges()):,} edges, drone keyframed on {frames} frames at 24 fps)" \
           in lines[0]
    assert lines[0].startswith(f"wrote {out / 'scene.blend'} (")
    assert lines[0].endswith(f"), {out / 'oblique.png'}, {out / 'top.png'}")


def test_a_new_process_prints_only_its_summary(bpy, run_folder, tmp_path):
    # Importing bpy 4.x prints NumPy 2's notice (with a traceback) about a module it ships
    # built for NumPy 1.x, and a headless machine's audio warning: the command keeps both
    # off the terminal, as it does Blender's other printing.
    result = run("blender", run_folder, "-o", tmp_path / "scene.blend")
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    [line] = result.stdout.splitlines()
    assert line.startswith(f"wrote {tmp_path / 'scene.blend'} (")


def test_blocks_are_cubes_in_their_colours(opened, run_folder):
    world = read_run(run_folder).world
    blocks = sorted(opened.collections["blocks"].objects, key=lambda obj: obj.name)
    assert len(blocks) == len(world.blocks) > 10
    for obj, box, color in zip(blocks, world.blocks, world.colors, strict=True):
        corners = np.array([obj.matrix_world @ v.co for v in obj.data.vertices])
        np.testing.assert_allclose(corners.min(axis=0), box[:3], atol=1e-5)
        np.testing.assert_allclose(corners.max(axis=0), box[3:], atol=1e-5)
        np.testing.assert_allclose(material_rgba(obj), (*linear_rgb(color), 1.0), atol=1e-6)


def test_boundary_is_a_black_box_of_alpha_0_344(opened, run_folder):
    world = read_run(run_folder).world
    boundary = opened.objects["boundary"]
    corners = np.array([boundary.matrix_world @ v.co for v in boundary.data.vertices])
    np.testing.assert_allclose(corners.min(axis=0), world.lower)
    np.testing.assert_allclose(corners.max(axis=0), world.upper)
    material = boundary.material_slots[0].material
    assert BOUNDARY_ALPHA == 0.344
    np.testing.assert_allclose(material.diffuse_color, (0, 0, 0, 0.344), atol=1e-6)
    shader = material.node_tree.nodes["Principled BSDF"]
    assert shader.inputs["Alpha"].default_value == pytest.approx(0.344)
    assert material.blend_method == "BLEND"
    # Faces turned inward, so culling the backs hides the walls nearest the camera.
    center = (world.lower + world.upper) / 2
    for polygon in boundary.data.polygons:
        assert np.dot(np.array(polygon.normal), np.array(polygon.center) - center) < 0


def test_start_and_goal_spheres(opened, run_folder):
    world = read_run(run_folder).world
    for name, point, rgb in (("start", world.start, (1, 0, 0)),
                             ("goal", world.goal, (0, 128 / 255, 0))):
        sphere = opened.objects[name]
        np.testing.assert_allclose(sphere.location, point, atol=1e-6)
        np.testing.assert_allclose(material_rgba(sphere), (*linear_rgb(rgb), 1.0), atol=1e-6)
        radius = np.linalg.norm([v.co for v in sphere.data.vertices], axis=1)
        np.testing.assert_allclose(radius, 0.02 * 12, rtol=1e-5)


def curve_points(obj) -> list[np.ndarray]:
    return [np.array([p.co[:3] for p in spline.points]) for spline in obj.data.splines]


def test_path_trajectory_and_thinned_tree(opened, run_folder):
    run_ = read_run(run_folder)
    (path,) = curve_points(opened.objects["path"])
    np.testing.assert_allclose(path, run_.path, atol=1e-5)
    np.testing.assert_allclose(material_rgba(opened.objects["path"]), (1, 0, 0, PATH_ALPHA))
    (trajectory,) = curve_points(opened.objects["trajectory"])
    np.testing.assert_allclose(trajectory, run_.trajectory.position, atol=1e-5)
    tree = curve_points(opened.objects["tree"])
    edges = run_.tree_edges()
    assert len(edges) > MAX_TREE_EDGES == len(tree)
    np.testing.assert_allclose(tree[0], edges[0], atol=1e-5)
    np.testing.assert_allclose(tree[-1], edges[-1], atol=1e-5)
    assert 0 < opened.objects["tree"].data.bevel_depth < opened.objects["path"].data.bevel_depth


def fcurves(obj):
    """The animation curves of ``obj`` (Blender 5 keeps them in the action's slots)."""
    action = obj.animation_data.action
    if hasattr(action, "fcurves"):
        return action.fcurves
    from bpy_extras.anim_utils import action_get_channelbag_for_slot

    return action_get_channelbag_for_slot(action, obj.animation_data.action_slot).fcurves


def test_drone_is_keyframed_along_the_flight(bpy, opened, run_folder):
    flight = read_run(run_folder).flight
    scene = bpy.context.scene
    frames = math.ceil(flight.t[-1] * FPS) + 1
    assert (scene.frame_start, scene.frame_end, scene.render.fps) == (1, frames, FPS)
    drone = opened.objects["drone"]
    paths = {(c.data_path, c.array_index): len(c.keyframe_points) for c in fcurves(drone)}
    assert paths == {**{("location", i): frames for i in range(3)},
                     **{("rotation_quaternion", i): frames for i in range(4)}}
    tilts = []
    for frame in (1, 2, frames // 3, frames // 2 + 7, frames - 1, frames):
        scene.frame_set(frame)
        row = np.flatnonzero(flight.t <= (frame - 1) / FPS + 1e-9)[-1]
        matrix = np.array(drone.matrix_world)
        np.testing.assert_allclose(matrix[:3, 3], flight.position[row], atol=1e-5)
        rotation = matrix[:3, :3] / drone.scale[0]
        np.testing.assert_allclose(rotation, to_matrix(flight.attitude[row]), atol=1e-5)
        tilts.append(math.degrees(math.acos(min(1.0, rotation[2, 2]))))
    assert row == len(flight.t) - 1  # the last frame shows the end of the flight
    assert max(tilts) > 0.5  # the attitude really changes along the flight


def test_cameras_frame_the_map(bpy, opened, run_folder):
    from bpy_extras.object_utils import world_to_camera_view
    from mathutils import Vector

    world = read_run(run_folder).world
    scene = bpy.context.scene
    assert (scene.render.resolution_x, scene.render.resolution_y) == SIZE
    assert opened.objects["top"].data.type == "ORTHO"
    assert opened.objects["oblique"].data.type == "PERSP"
    corners = [Vector(np.where([i & 1, i & 2, i & 4], world.upper, world.lower))
               for i in range(8)]
    for name in ("oblique", "top"):
        view = np.array([world_to_camera_view(scene, opened.objects[name], corner)
                         for corner in corners])
        assert np.all(view[:, :2] > 0.0) and np.all(view[:, :2] < 1.0), name
        assert np.all(view[:, 2] > 0.0)  # in front of the camera
        # Framed, not lost in the middle: the map spans most of the width or height.
        assert np.max(np.ptp(view[:, :2], axis=0)) > 0.85, name


@pytest.mark.parametrize("camera", ["oblique", "top"])
def test_renders_show_the_scene(written, camera):
    image = imread(written[0] / f"{camera}.png")[..., :3]
    assert image.shape[:2] == SIZE[::-1]
    colors = np.unique((image * 255).round().astype(np.uint8).reshape(-1, 3), axis=0)
    assert len(colors) > 500
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    pixels = image.shape[0] * image.shape[1]
    assert np.sum(np.all(image > 0.99, axis=-1)) > 0.2 * pixels  # the white background
    grey = (np.ptp(image, axis=-1) < 0.02) & (r > 0.5) & (r < 0.8)
    assert np.sum(grey) > 0.1 * pixels  # the floor and far walls seen through the boundary
    assert np.sum((r > 0.3) & (g < 0.45 * r) & (b < 0.45 * r)) > 20  # the start and path
    assert np.sum((g > r + 0.1) & (g > b + 0.1)) > 50  # the goal and the green branches
    assert np.sum((r > g + 0.05) & (g > b + 0.05) & (g > 0.45 * r)) > 25  # brown trunks


def one_line_error(capsys, *args: str) -> str:
    """Run the command in this process; it must exit 2 with one line on stderr."""
    code = main(["blender", *args])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and err.startswith("quadnav: error: "), err
    return err


def test_unknown_camera_is_a_one_line_error(run_folder, tmp_path, capsys):
    err = one_line_error(capsys, str(run_folder), "-o", str(tmp_path / "scene.blend"),
                         "--render", str(tmp_path / "side.png"))
    assert "side.png: expected a render named by its camera: oblique.png or top.png" in err
    assert list(tmp_path.iterdir()) == []


def test_without_bpy_says_how_to_install(run_folder, tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "bpy", None)  # import bpy now fails as if not installed
    err = one_line_error(capsys, str(run_folder), "-o", str(tmp_path / "scene.blend"))
    assert "pip install 'quadnav[blender]'" in err
    assert list(tmp_path.iterdir()) == []
