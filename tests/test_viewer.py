"""The HTML viewer: ``quadnav view``, ``quadnav fly --html``, and the page in a real browser.

The browser tests drive Debian's chromium through chromedriver (selenium, the ``browser``
fixture of conftest.py); they skip when either is missing (``apt-get install chromium
chromium-driver``, ``pip install selenium``).
"""

from __future__ import annotations

import dataclasses
import html
import io
import json
import re
import shutil

import numpy as np
import pytest
from clitools import assert_user_error, run_here
from PIL import Image

from quadnav.cli.main import main
from quadnav.mission import MissionSettings, fly_mission
from quadnav.planning import PlannerSettings
from quadnav.report.run_writer import write_run
from quadnav.runs import VIEW_PAGE, RunContent, read_run
from quadnav.viz.html_viewer import (
    MAX_TREE_EDGES,
    viewer_data,
    viewer_html,
    write_viewer,
)
from quadnav.world import World, load_world

SMALL = "forest:size=12x12x4,seed=2"
#: Most bytes a page of the small run may take (the tree, thinned, dominates).
MAX_PAGE_BYTES = 3_000_000
#: Fewest distinct colours in a screenshot of a drawn scene (a blank canvas has one).
MIN_COLOURS = 500
#: One worker runs this module: the browser and the module fixtures' runs are made once.
pytestmark = pytest.mark.xdist_group("viewer-browser")

#: The flown track's colour in the page (viewer.js: FLOWN).
FLOWN_RGB = (17, 17, 17)
READOUT = re.compile(r"t = ([\d.]+) s\s+position \(([-\d.]+), ([-\d.]+), ([-\d.]+)\) m"
                     r"\s+speed ([\d.]+) m/s")


@pytest.fixture(scope="module")
def flown(tmp_path_factory):
    """A run folder of a successful flight, written with ``--html``, and the fly result;
    searched for the fixed budget (``--stall 0``), whose tree is large enough to thin."""
    folder = tmp_path_factory.mktemp("flown")
    result = run_here("fly", SMALL, "--stall", "0", "-o", folder, "--quiet", "--no-figures",
                      "--html")
    assert result.returncode == 0, result.stderr
    return folder, result


@pytest.fixture(scope="module")
def unsolved(tmp_path_factory):
    """A run folder of a search that found no path (20 samples are too few)."""
    folder = tmp_path_factory.mktemp("unsolved")
    mission = fly_mission(load_world(SMALL),
                          settings=MissionSettings(planning=PlannerSettings(max_iterations=20)))
    assert mission.flight is None
    write_run(mission, folder, figures=False)
    write_viewer(read_run(folder), folder / VIEW_PAGE)
    return folder


def _page_data(page: str) -> dict:
    match = re.search(r'<script id="run-data" type="application/json">(.*?)</script>', page, re.S)
    return json.loads(match[1])


def test_fly_html_writes_a_self_contained_page(flown):
    folder, result = flown
    page_path = folder / "view.html"
    assert str(page_path) in result.stdout
    page = page_path.read_text(encoding="utf-8")
    assert 10_000 < len(page.encode()) < MAX_PAGE_BYTES
    # The only URLs are strings the vendored three.js holds (a namespace name, a link in a
    # warning's text); nothing is fetched: no src, no href but data.
    urls = set(re.findall(r"https?://[^\s\"'<>)]+", page))
    assert urls <= {"http://www.w3.org/1999/xhtml", "https://github.com/mrdoob/three.js/pull/23228"}
    for tag in re.findall(r"<(?:script|link|img|iframe)\b[^>]*>", page):
        assert not re.search(r"\bsrc=", tag), tag
        assert not re.search(r"\bhref=(?![\"']data:)", tag), tag
    data = _page_data(page)
    metrics = json.loads((folder / "metrics.json").read_text())
    assert data["metrics"] == metrics and data["title"] == metrics["map"]
    assert data["treeEdges"] > MAX_TREE_EDGES  # so the thinning is exercised
    assert len(data["tree"]) == 6 * MAX_TREE_EDGES
    flight = read_run(folder).flight
    assert len(data["flight"]["t"]) == len(flight.t)
    assert data["flight"]["position"][-3:] == pytest.approx(flight.position[-1], abs=1e-3)


def test_view_writes_the_same_page_as_fly(flown, tmp_path):
    folder, _ = flown
    copy = shutil.copytree(folder, tmp_path / "copy", ignore=shutil.ignore_patterns("*.html"))
    result = run_here("view", copy)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == f"wrote {copy / 'view.html'}"
    assert (copy / "view.html").read_bytes() == (folder / "view.html").read_bytes()


def test_a_run_without_a_path_has_no_flight_data(unsolved):
    data = viewer_data(read_run(unsolved))
    assert data["path"] is data["trajectory"] is data["flight"] is None
    assert data["blocks"] and data["tree"] and data["metrics"]["path_found"] is False
    assert data["subtitle"].startswith("FAILED: no path found")


def test_text_from_the_run_cannot_break_out_of_the_page(unsolved):
    name = "</script><script>alert(1)</script> & <b>"
    original = read_run(unsolved)
    page = viewer_html(dataclasses.replace(original, metrics={**original.metrics, "map": name}))
    assert page.count("</script>") == 3  # the data's, three.js' and the viewer's
    assert f"<title>quadnav: {html.escape(name)}</title>" in page
    data = _page_data(page)
    assert data["title"] == data["metrics"]["map"] == name


def test_view_bad_input_is_one_line(tmp_path, flown, capsys):
    assert_user_error(run_here("view", tmp_path), str(tmp_path), "not a quadnav fly or track output folder")
    folder, _ = flown
    page = tmp_path / "no/such/dir/page.html"
    assert main(["view", str(folder), "-o", str(page)]) == 2
    error = capsys.readouterr().err
    assert error == f"quadnav: error: {page}: folder {str(page.parent)!r} does not exist\n"
    assert not list(tmp_path.iterdir())


# ---------------------------------------------------------------- in a real browser


def _open(driver, page) -> None:
    """Load the page and wait until the canvas has been drawn."""
    from selenium.webdriver.support.ui import WebDriverWait

    driver.get(page.as_uri())
    WebDriverWait(driver, 10, poll_frequency=0.05).until(
        lambda d: d.execute_script("return Number(document.getElementById('view')"
                                   ".dataset.frames || 0)") > 0)


def _canvas_png(driver) -> bytes:
    return driver.find_element("id", "view").screenshot_as_png


def _colours(png: bytes) -> int:
    return len(Image.open(io.BytesIO(png)).convert("RGB").getcolors(1 << 24))


def _redrawn(driver, before: bytes) -> bytes:
    """The canvas once it differs from ``before`` (drawing waits for the next frame)."""
    from selenium.webdriver.support.ui import WebDriverWait

    return WebDriverWait(driver, 5, poll_frequency=0.05).until(
        lambda d: (png := _canvas_png(d)) != before and png)


def _errors(driver) -> list[dict]:
    return [entry for entry in driver.get_log("browser") if entry["level"] == "SEVERE"]


def _readout(driver) -> tuple[float, ...]:
    text = driver.find_element("id", "readout").text
    match = READOUT.search(text)
    assert match, text
    return tuple(map(float, match.groups()))


def test_the_page_draws_the_run_without_errors(browser, flown):
    folder, _ = flown
    _open(browser, folder / "view.html")
    canvas = browser.find_element("id", "view")
    assert canvas.size["width"] > 400 and canvas.size["height"] > 300
    assert _colours(_canvas_png(browser)) > MIN_COLOURS
    metrics = json.loads((folder / "metrics.json").read_text())
    rows = browser.find_elements("css selector", "#metrics tr")
    assert len(rows) == len(metrics)
    assert browser.find_element("id", "timebar").is_displayed()
    ticks = browser.find_element("id", "scale-ticks").text.split()
    top_speed = np.linalg.norm(read_run(folder).trajectory.velocity, axis=1).max()
    assert ticks[0] == "0.00" and float(ticks[-1]) == pytest.approx(top_speed, abs=0.01)
    assert _errors(browser) == []


def test_the_slider_and_play_move_the_drone(browser, flown):
    from selenium.webdriver.support.ui import WebDriverWait

    folder, _ = flown
    _open(browser, folder / "view.html")
    metrics = json.loads((folder / "metrics.json").read_text())
    assert _readout(browser) == pytest.approx((0, *metrics["start"], 0), abs=1e-2)
    before = _canvas_png(browser)
    browser.execute_script("const s = document.getElementById('time');"
                           "s.value = s.max; s.dispatchEvent(new Event('input'));")
    t, x, y, z, _ = _readout(browser)
    assert t == pytest.approx(metrics["flight_time_s"], abs=0.01)
    assert (x, y, z) == pytest.approx(metrics["goal"], abs=0.02)
    _redrawn(browser, before)  # the drone marker moved
    browser.find_element("id", "play").click()  # from the end: plays again from the start
    WebDriverWait(browser, 10, poll_frequency=0.05).until(
        lambda d: 0.2 < _readout(d)[0] < metrics["flight_time_s"])
    # Read while playing and pressed at once: WebDriver's own commands wait on the frames
    # the playing draws, seconds of them in a software-rendered headless browser.
    shown = browser.execute_script("const play = document.getElementById('play');"
                                   "const shown = play.textContent; play.click(); return shown;")
    assert shown == "pause"
    assert browser.find_element("id", "play").text == "play"  # paused
    assert _errors(browser) == []


def test_dragging_and_the_wheel_change_the_view(browser, flown):
    from selenium.webdriver import ActionChains
    from selenium.webdriver.common.actions.wheel_input import ScrollOrigin

    folder, _ = flown
    _open(browser, folder / "view.html")
    canvas = browser.find_element("id", "view")
    before = _canvas_png(browser)
    ActionChains(browser).drag_and_drop_by_offset(canvas, 120, 40).perform()
    rotated = _redrawn(browser, before)
    ActionChains(browser).scroll_from_origin(ScrollOrigin.from_element(canvas), 0, -300).perform()
    zoomed = _redrawn(browser, rotated)
    assert _colours(zoomed) > MIN_COLOURS
    assert _errors(browser) == []


def test_a_run_without_a_path_draws_map_tree_and_metrics(browser, unsolved):
    _open(browser, unsolved / "view.html")
    assert _colours(_canvas_png(browser)) > MIN_COLOURS / 5
    labels = browser.find_element("id", "layers").text
    assert "blocks" in labels and re.search(r"tree \(\d+ edges\)", labels)
    assert _layer_box(browser, "tree").is_selected()  # nothing to bury: shown at first
    assert "trajectory" not in labels and "drone" not in labels
    assert not browser.find_element("id", "timebar").is_displayed()
    assert browser.find_elements("css selector", "#metrics tr")
    assert _errors(browser) == []


@pytest.fixture(scope="module")
def pillar(tmp_path_factory):
    """A viewer page of one blue block and a red path behind it (seen from -y), in front of
    it (seen from +y): the pixel where the path crosses the block tells depth apart."""
    world = World(np.array([0.0, 0, 0, 10, 10, 4]), np.array([[4.0, 4, 0, 6, 6, 4]]),
                  colors=np.array([[0.0, 0.0, 1.0]]), name="pillar")
    folder = tmp_path_factory.mktemp("pillar")
    path = np.array([[2.0, 8, 2], [8, 8, 2]])
    write_run(RunContent(world, {"map": "pillar", "success": True}, {}, None, path, None, None),
              folder, figures=False, html=True)
    return folder / VIEW_PAGE


def _pixel(driver, point) -> tuple[int, int, int]:
    """The colour drawn at the screen position of ``point`` (3,), m."""
    x, y = driver.execute_script("return quadnavViewer.screenOf(arguments[0])", list(point))
    image = Image.open(io.BytesIO(_canvas_png(driver))).convert("RGB")
    return image.getpixel((round(x), round(y)))


def _set_view(driver, azimuth: float, elevation: float) -> None:
    """Turn the camera to ``azimuth`` and ``elevation`` (degrees) and wait for the frame
    drawn after."""
    from selenium.webdriver.support.ui import WebDriverWait

    frames = driver.execute_script("return Number(document.getElementById('view')"
                                   ".dataset.frames)")
    driver.execute_script(f"quadnavViewer.setView({azimuth}, {elevation})")
    WebDriverWait(driver, 5, poll_frequency=0.05).until(
        lambda d: d.execute_script(
            "return Number(document.getElementById('view').dataset.frames)") > frames)


def test_a_block_in_front_hides_what_is_behind_it(browser, pillar):
    _open(browser, pillar)
    crossing = (5.0, 8.0, 2.0)  # on the path, straight behind the block's middle from -y
    for azimuth, path_in_front in ((-90, False), (90, True)):
        _set_view(browser, azimuth, 10)
        red, green, blue = _pixel(browser, crossing)
        if path_in_front:
            assert red > 150 and blue < 100, (red, green, blue)  # the path's red
        else:
            assert blue > 100 and red < 60, (red, green, blue)  # the block's blue
    assert _errors(browser) == []


@pytest.fixture(scope="module")
def tello_truth(tmp_path_factory):
    """The view page of a Tello run along the room (:func:`tellotools.planned_room`),
    written as ``tello fly`` writes it: the dead-reckoned track along y = 1 m, and the
    true track 0.4 m beside it."""
    from tellotools import planned_room

    from quadnav.hardware.bridge.dead_reckoning import Estimate
    from quadnav.hardware.bridge.flight import BridgeSettings, Flown, Outcome, Status
    from quadnav.hardware.bridge.run_record import tello_run_content

    t, x = np.linspace(0.0, 10.0, 21), np.linspace(0.5, 3.5, 21)
    track = np.column_stack([t, x, np.full(21, 1.0), np.full(21, 0.8)])
    truth = np.column_stack([t, x, np.full(21, 1.4), np.full(21, 0.8)])
    landing = Estimate(np.array([3.5, 1.0, 0.0]), 0.05)
    flown = Flown(Outcome(Status.LANDED, "landed", landing=landing), track, truth)
    folder = tmp_path_factory.mktemp("tello_truth")
    write_run(tello_run_content(planned_room(), BridgeSettings(), flown, "198.18.67.1"),
              folder, figures=False, html=True)
    return folder / VIEW_PAGE


def test_a_tello_runs_true_track_is_drawn_beside_its_estimate(browser, tello_truth):
    _open(browser, tello_truth)
    labels = browser.find_element("id", "layers").text
    assert "flown track" in labels and "true track" in labels
    _set_view(browser, -90, 80)  # nearly from above
    on_truth = (2.0, 1.4, 0.8)  # halfway along, where nothing else is drawn
    assert _purple_near(browser, on_truth)  # the true track's
    _toggle(browser, "true track")
    assert not _purple_near(browser, on_truth)  # hidden with its layer
    assert _errors(browser) == []


def _purple_near(driver, point, reach: int = 3) -> bool:
    """Whether a pixel within ``reach`` px of the screen position of ``point`` (3,), m, is
    purple (the true track's #9467bd, blended with white at its edges: red and blue well
    above green, unlike the tree's blue, the path's red or the floor's grey)."""
    x, y = driver.execute_script("return quadnavViewer.screenOf(arguments[0])", list(point))
    image = Image.open(io.BytesIO(_canvas_png(driver))).convert("RGB")
    pixels = [image.getpixel((round(x) + dx, round(y) + dy))
              for dx in range(-reach, reach + 1) for dy in range(-reach, reach + 1)]
    return any(red > green + 20 and blue > green + 40 for red, green, blue in pixels)


def _layer_box(driver, name: str):
    """The checkbox of the layer whose label starts with ``name``."""
    return next(label for label in driver.find_elements("css selector", "#layers label")
                if label.text.startswith(name)).find_element("tag name", "input")


def _pixels_at(driver, points) -> np.ndarray:
    """The colours (n, 3) drawn at the screen positions of ``points`` (n, 3), m."""
    image = Image.open(io.BytesIO(_canvas_png(driver))).convert("RGB")
    spots = driver.execute_script("return arguments[0].map(quadnavViewer.screenOf)",
                                  np.asarray(points).tolist())
    return np.array([image.getpixel((round(x), round(y))) for x, y in spots], dtype=int)


def _toggle(driver, name: str) -> None:
    """Click the checkbox of the layer ``name`` and wait for the new drawing."""
    before = _canvas_png(driver)
    _layer_box(driver, name).click()
    _redrawn(driver, before)


def test_the_page_opens_with_the_lines_on_top_and_the_tree_off(browser, flown):
    """The path, trajectory and flown track are what a reader looks for: the page opens
    without the tree (20,000 edges would bury them), and the tree, once turned on, is drawn
    beneath them: wherever the flown track shows along the flight, it still does."""
    folder, _ = flown
    _open(browser, folder / "view.html")
    shown = {label.text.split(" (")[0]: label.find_element("tag name", "input").is_selected()
             for label in browser.find_elements("css selector", "#layers label")}
    assert shown == {"blocks": True, "tree": False, "path": True, "trajectory": True,
                     "flown track": True}
    along = read_run(folder).flight.position[::10]
    track = (_pixels_at(browser, along) == FLOWN_RGB).all(axis=1)
    assert track.sum() >= 10  # elsewhere a block or the goal hides it, or it is antialiased
    _toggle(browser, "tree")
    still = (_pixels_at(browser, along) == FLOWN_RGB).all(axis=1)
    assert still[track].all(), np.flatnonzero(track & ~still)
    assert _errors(browser) == []
