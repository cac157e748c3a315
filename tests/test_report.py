"""The HTML run report: written by ``quadnav fly``, and ``quadnav report DIR [DIR ...]``
over real runs; self-contained, with the figures, metrics and parameters of each run."""

from __future__ import annotations

import base64
import io
import json
import re
import shutil

import pytest
from clitools import assert_user_error, run_here
from PIL import Image

from quadnav.cli.main import main
from quadnav.mission import MissionSettings, fly_mission
from quadnav.planning import PlannerSettings
from quadnav.report.html_report import flatten
from quadnav.report.run_writer import write_run
from quadnav.runs import FIGURES, REPORT
from quadnav.world import load_world

#: One worker runs this module: the runs of the module fixtures are made once.
pytestmark = pytest.mark.xdist_group("report-runs")

SMALL = "forest:size=12x12x4,seed=2"
IMAGE = re.compile(r'<img src="data:image/png;base64,([A-Za-z0-9+/=]+)" '
                   r'width="(\d+)" height="(\d+)"')
#: Pixel sizes of the four figures (inches times 120 dpi).
SIZES = [(1440, 840), (1560, 960), (1200, 480), (1320, 1080)]


@pytest.fixture(scope="module")
def flown(tmp_path_factory):
    """A run by ``quadnav fly`` with its figures and report."""
    folder = tmp_path_factory.mktemp("flown") / "out"
    result = run_here("fly", SMALL, "-o", folder, "--quiet")
    assert result.returncode == 0, result.stderr
    assert str(folder / REPORT) in result.stdout
    return folder


@pytest.fixture(scope="module")
def plain(tmp_path_factory):
    """A run by ``quadnav fly --no-figures`` (in this process; another seed, another
    path): no figures, so no report."""
    folder = tmp_path_factory.mktemp("plain") / "out"
    assert main(["fly", SMALL, "--seed", "3", "-o", str(folder), "--quiet",
                 "--no-figures"]) == 0
    assert not any((folder / name).exists() for name in (*FIGURES, REPORT))
    return folder


@pytest.fixture(scope="module")
def pathless(tmp_path_factory):
    """A run whose search stopped after one sample, without a path."""
    folder = tmp_path_factory.mktemp("pathless")
    settings = MissionSettings(planning=PlannerSettings(seed=0, max_iterations=1))
    write_run(fly_mission(load_world(SMALL), settings=settings), folder, figures=False)
    return folder


def images(html: str) -> list[bytes]:
    """The embedded PNGs of a report, each checked to decode to its stated size."""
    found = []
    for data, width, height in IMAGE.findall(html):
        png = base64.b64decode(data, validate=True)
        with Image.open(io.BytesIO(png)) as image:
            image.load()
            assert image.format == "PNG" and image.size == (int(width), int(height))
        found.append(png)
    assert len(found) == html.count("<img ")
    return found


def assert_self_contained(html: str) -> None:
    """Nothing fetched from elsewhere: no scripts, stylesheets or outside links."""
    assert html.startswith("<!DOCTYPE html>") and html.rstrip().endswith("</html>")
    for banned in ("http://", "https://", "<script", "<link", "url(", "@import"):
        assert banned not in html, banned
    assert all(src.startswith("data:image/png;base64,")
               for src in re.findall(r'src="([^"]*)"', html))
    assert all(href.startswith("#") for href in re.findall(r'href="([^"]*)"', html))
    assert "<style>" in html


def sections(html: str) -> list[str]:
    return html.split("<section ")[1:]


def test_fly_writes_a_self_contained_report_of_the_run(flown):
    html = (flown / REPORT).read_text(encoding="utf-8")
    assert_self_contained(html)
    assert images(html) == [(flown / name).read_bytes() for name in FIGURES]
    metrics = json.loads((flown / "metrics.json").read_text())
    (section,) = sections(html)
    assert f"Run 1: {metrics['map']}" in section and "success" in section
    for heading in ("Figures", "Metrics", "Parameters"):
        assert f"<h3>{heading}</h3>" in section
    for key, value in metrics.items():
        assert f"<code>{key}</code>" in section, key
        if isinstance(value, float):
            assert f"{value:.6g}" in section, key
    assert f"tracking error RMS {100 * metrics['rms_tracking_error_m']:.2f} cm" in section
    parameters = json.loads((flown / "parameters.json").read_text())
    names = [name for name, _ in flatten(parameters)]
    for name in ("vehicle.mass", "gains.position.kp", "simulation.control_rate",
                 "trajectory.v_max", "planning.seed"):
        assert name in names
    for name in names:
        assert f"<code>{name}</code>" in section, name
    mass = parameters["vehicle"]["mass"]
    assert f'<code>vehicle.mass</code></td><td class="value">{mass:.6g}</td>' in section


def test_one_report_over_several_runs(flown, plain, pathless, tmp_path, capsys):
    out = tmp_path / "all.html"
    assert main(["report", str(flown), str(plain), str(pathless), "-o", str(out)]) == 0
    assert capsys.readouterr().out.strip() == f"wrote {out} (3 runs)"
    html = out.read_text(encoding="utf-8")
    assert_self_contained(html)
    parts = sections(html)
    assert [part.split('"')[1] for part in parts] == ["run-1", "run-2", "run-3"]
    overview = html[html.index("<h2>Overview</h2>"):html.index("<section ")]
    assert [f'href="#run-{k}"' in overview for k in (1, 2, 3)] == [True] * 3
    for part, folder in zip(parts, (flown, plain, pathless), strict=True):
        metrics = json.loads((folder / "metrics.json").read_text())
        assert f"folder {folder};" in part
        length = metrics["path_length_m"]
        assert ("—" if length is None else f"{length:.6g}") in part
    lengths = [json.loads((f / "metrics.json").read_text())["path_length_m"]
               for f in (flown, plain)]
    assert lengths[0] != lengths[1]  # two different runs, each in its own section
    assert images(parts[0]) == [(flown / name).read_bytes() for name in FIGURES]
    # A folder without figures gets them drawn from its files (and keeps none).
    assert [Image.open(io.BytesIO(png)).size for png in images(parts[1])] == SIZES
    assert not any((plain / name).exists() for name in (*FIGURES, REPORT))
    assert len(images(parts[2])) == 1 and "no path" in parts[2]  # the map and tree only


def test_one_folder_reports_into_it_by_default(flown, tmp_path, capsys, monkeypatch):
    folder = tmp_path / "copy"
    shutil.copytree(flown, folder)
    assert main(["report", str(folder)]) == 0
    assert capsys.readouterr().out.strip() == f"wrote {folder / REPORT} (1 run)"
    assert f"folder {folder};" in (folder / REPORT).read_text(encoding="utf-8")
    monkeypatch.chdir(tmp_path)  # several folders: report.html here
    assert main(["report", str(folder), str(flown)]) == 0
    assert len(sections((tmp_path / REPORT).read_text(encoding="utf-8"))) == 2


def test_a_bad_folder_is_one_line_exit_2_and_writes_nothing(flown, tmp_path):
    out = tmp_path / "all.html"
    assert_user_error(run_here("report", flown, tmp_path / "nowhere", "-o", out),
                      "nowhere", "not a quadnav fly or track output folder")
    assert not out.exists()


@pytest.mark.parametrize(("name", "fragment"), [
    ("report.pdf", "expected a file name ending in .html"),
    ("missing/report.html", "does not exist"),
])
def test_a_bad_output_is_one_line_exit_2(flown, tmp_path, capsys, name, fragment):
    assert main(["report", str(flown), "-o", str(tmp_path / name)]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert name in line and fragment in line
    assert list(tmp_path.iterdir()) == []
