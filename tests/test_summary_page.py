"""The batch summary page over many maps with long path-like names: short labels that fit
the figures, each map's full name on hover and in the table, panels that never overlap,
figures that grow with the maps, no matplotlib warning; and the page in Chromium."""

from __future__ import annotations

import io
import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from figurecheck import assert_labels_apart, assert_texts_off_other_axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from PIL import Image

from quadnav.batch.summary import summary
from quadnav.batch.summary_page import (
    MAP_LABEL_WIDTH,
    _Groups,
    distributions,
    heat_map,
    short_maps,
    summary_html,
)
from quadnav.batch.table import NAMES

#: One worker for the module, so that its module-scoped fixtures are built once under
#: --dist loadgroup (each test apart would build them on each worker).
pytestmark = pytest.mark.xdist_group("summary-page")

#: Thirteen course maps as a student keeps them: deep folders, long file names.
LONG_NAMES = [f"/home/student/courses/rbe595/project{k % 3}/maps/test_sets/set_{k:02d}/"
              f"obstacle_course_with_a_long_descriptive_name_{k:02d}.txt" for k in range(13)]
#: Three planners, so the heat map has three panels side by side and under one another.
PLANNERS = ("rrtstar", "ompl:BITstar", "ompl:RRTConnect")


def batch_rows(maps: list[str], planners=PLANNERS, speeds=(1.0, 2.0), seeds: int = 3
               ) -> list[dict]:
    """Rows of results.csv for every map x planner x speed x seed, as a batch writes them
    (drawn starts and goals), with outcomes and metrics that vary from row to row."""
    rows = []
    for k, name in enumerate(maps):
        for planner in planners:
            for speed in speeds:
                for seed in range(seeds):
                    n = k + seed + len(planner) + int(speed)
                    rows.append(dict.fromkeys(NAMES) | {
                        "map": name, "seed": seed, "speed": speed, "wind_x": 0.0,
                        "wind_y": 0.0, "wind_z": 0.0, "gusts": 0.0, "spread": "none",
                        "planner": planner, "gains": "default", "start_goal_drawn": True,
                        "margin_m": 0.2, "success": n % 4 != 0, "error": None,
                        "rms_tracking_error_m": 0.01 + 0.004 * (n % 7),
                        "min_clearance_m": 0.2 + 0.03 * (n % 5),
                        "trajectory_duration_s": 10.0 + n % 6})
    return rows


def _labels(maps: list[str], planners=PLANNERS, speeds=(1.0, 2.0)) -> _Groups:
    rows = batch_rows(maps, planners, speeds)
    return _Groups(summary(rows, len(rows))["groups"])


@pytest.mark.parametrize(("planners", "speeds"), [
    (PLANNERS[:1], (1.0, 2.0)), (PLANNERS, (1.0, 2.0)), (PLANNERS[:1], tuple(range(1, 11)))],
    ids=["one panel", "three", "ten speeds"])
def test_long_map_names_fit_the_heat_map_without_a_warning(planners, speeds):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # "constrained_layout not applied ..." among them
        fig, shown = heat_map(_labels(LONG_NAMES, planners, speeds))
        FigureCanvasAgg(fig)
        assert_labels_apart(fig, min_ticks=1)
        assert_texts_off_other_axes(fig)
    labels = [text.get_text() for text in shown]
    assert len(labels) == 13 * (1 if len(planners) == 1 else 2)  # the first panel of a line
    assert all(len(label) <= MAP_LABEL_WIDTH for label in labels)
    assert set(shown.values()) == set(LONG_NAMES)


def test_long_plugin_specs_title_their_panels_within_them():
    # planners of your own, by file and arguments: each panel's title is wrapped to its width
    planners = ("/home/student/p1/my_planners.py:graph_search(resolution=0.25)",
                "/home/student/p1/my_planners.py:probabilistic_roadmap(samples=500)",
                "rrtstar")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig, _ = heat_map(_labels(["maps/a.txt", "maps/b.txt"], planners))
        FigureCanvasAgg(fig)
        assert_texts_off_other_axes(fig)
    renderer = fig.canvas.get_renderer()
    for ax in (ax for ax in fig.axes if ax.get_title()):
        box = ax.title.get_window_extent(renderer)
        assert ax.bbox.x0 - 1 <= box.x0 and box.x1 <= ax.bbox.x1 + 1, ax.get_title()
    assert [ax.get_title() for ax in fig.axes if ax.get_title()][:2] == [
        "my_planners.py:\ngraph_search(\nresolution=0.25)",
        "my_planners.py:\nprobabilistic_roadmap(\nsamples=500)"]


def test_the_heat_map_grows_with_the_maps_and_keeps_its_cells_readable():
    heights = []
    for count in (2, 13, 40):
        maps = [f"maps/m{k:02d}.txt" for k in range(count)]
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            fig, _ = heat_map(_labels(maps))
            FigureCanvasAgg(fig)
            assert_texts_off_other_axes(fig)  # no cell's two lines on another's
        heights.append(fig.get_figheight())
    assert heights[0] < heights[1] < heights[2]
    assert (heights[2] - heights[1]) / 27 == pytest.approx((heights[1] - heights[0]) / 11)


def test_the_distributions_of_many_groups_fit_without_a_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig, shown = distributions(_labels(LONG_NAMES), batch_rows(LONG_NAMES))
        FigureCanvasAgg(fig)
        assert_labels_apart(fig, min_ticks=1)
        assert_texts_off_other_axes(fig)
    assert len(shown) == 13 * 3 * 2
    assert all(full.split(", ")[0] in LONG_NAMES for full in shown.values())


@pytest.mark.parametrize(("names", "labels"), [
    (["maps/a.txt", "other/b.json", "forest:seed=3"], ["a.txt", "b.json", "forest:seed=3"]),
    (["x/set1/map.txt", "x/set2/map.txt"], ["set1/map.txt", "set2/map.txt"]),
    ([LONG_NAMES[0]], ["obstacle_c\u2026scriptive_name_00.txt"]),
    ([f"maps/{'n' * 20}{middle}{'n' * 20}.txt" for middle in "ab"],  # cut, they read the same
     [f"{k}. {'n' * 7}\u2026{'n' * 17}.txt" for k in (1, 2)]),
])
def test_a_map_is_labelled_by_the_end_of_its_path_that_tells_it_apart(names, labels):
    assert list(short_maps(names).values()) == labels
    assert all(len(label) <= MAP_LABEL_WIDTH for label in labels)


@pytest.fixture(scope="module")
def page(tmp_path_factory) -> Path:
    """The summary page of 13 maps x 3 planners x 2 speeds x 3 seeds."""
    rows = batch_rows(LONG_NAMES)
    folder = tmp_path_factory.mktemp("batch")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        text = summary_html(json.loads(json.dumps(summary(rows, len(rows)))), rows, folder)
    path = folder / "summary.html"
    path.write_text(text, encoding="utf-8")
    return path


def test_the_page_names_every_map_in_full(page):
    text = page.read_text(encoding="utf-8")
    for name in LONG_NAMES:
        assert f'title="{name}"' in text  # on its heat-map label
        assert f'title="{name}, 1 m/s, ompl:BITstar"' in text  # on its box plots' label
        assert name.replace("/", "/<wbr>").replace("_", "_<wbr>") in text  # in the table


def _tooltips(driver) -> list[dict]:
    """Each tooltip of the page: its title, its box within its image (CSS px), the image's
    index, and the element the browser finds at the box's centre."""
    return driver.execute_script("""
        const images = [...document.querySelectorAll('.tooltips img')];
        return [...document.querySelectorAll('.tooltips .tooltip')].map((spot) => {
          spot.scrollIntoView({block: 'center'});
          const image = spot.parentElement.querySelector('img');
          const box = spot.getBoundingClientRect(), frame = image.getBoundingClientRect();
          const hit = document.elementFromPoint(box.x + box.width / 2, box.y + box.height / 2);
          return {title: spot.title, image: images.indexOf(image), hit: hit === spot,
                  box: [box.x - frame.x, box.y - frame.y, box.width, box.height]};
        });""")


def _dark_pixels(png: bytes, box) -> int:
    """Pixels darker than mid-grey in ``box`` (x, y, width, height, CSS px) of the image."""
    image = np.asarray(Image.open(io.BytesIO(png)).convert("L"), dtype=int)
    x, y, width, height = (round(v) for v in box)
    return int((image[y:y + height, x:x + width] < 128).sum())


@pytest.mark.parametrize("window_width", [1280, 960])
def test_in_chromium_the_page_fits_and_each_label_shows_its_full_name(browser, page, tmp_path,
                                                                      window_width):
    """Screenshots of the page in a real browser, at two widths: no sideways scrolling,
    and every tooltip lies on its drawn label (dark text under it) and is what the pointer
    finds there."""
    browser.set_window_size(window_width, 900)
    try:
        browser.get(page.as_uri())
        width = browser.execute_script("return document.documentElement.scrollWidth")
        assert width <= browser.execute_script("return window.innerWidth"), width
        tooltips = _tooltips(browser)
        assert len(tooltips) == 13 * 2 + 13 * 3 * 2
        assert {t["title"] for t in tooltips} >= set(LONG_NAMES)
        assert all(t["hit"] for t in tooltips), [t for t in tooltips if not t["hit"]][:3]
        height = browser.execute_script("return document.documentElement.scrollHeight")
        browser.set_window_size(window_width, min(height + 200, 16_000))
        images = browser.find_elements("css selector", ".tooltips img")
        shots = [image.screenshot_as_png for image in images]
        browser.save_screenshot(str(tmp_path / "summary.png"))
        for tooltip in _tooltips(browser):
            assert _dark_pixels(shots[tooltip["image"]], tooltip["box"]) > 20, tooltip
    finally:
        browser.set_window_size(1280, 860)
