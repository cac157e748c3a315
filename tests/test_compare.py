"""``quadnav compare``: the leaderboard of a real batch over two controllers and two planners
(a built-in one and a plain-Python one) on a course map shipped with quadnav, its intervals
and tests checked against the rows by closed formulas and counts here; the page in a real
browser; bad folders."""

from __future__ import annotations

import csv
import io
import json
import math
import shutil
import statistics
from pathlib import Path

import numpy as np
import pytest
from clitools import assert_user_error, run_here
from figurecheck import assert_labels_apart, assert_texts_off_other_axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from PIL import Image

from quadnav.batch.compare import compare, holm, mcnemar, signed_rank
from quadnav.batch.compare_page import leaderboard_figure
from quadnav.batch.table import UNTIMED_NAMES, read_rows
from quadnav.pages import breakable

#: One worker for the module, so that its module-scoped fixtures are built once under
#: --dist loadgroup (each test apart would build them on each worker).
pytestmark = pytest.mark.xdist_group("compare")

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
PLANNER = "plain_planner.py:graph_search(resolution=0.5)"
# A steady side wind (0.11 N on the 80 g Tello): the cascade's integral holds the goal (the
# flights end 4 cm or less from it), the SE(3) controller, without one, ends 20 cm or more
# off, beyond the 10 cm tolerance: a clear split, whatever the machine.
SPEC = f"""\
seeds = 4
speeds = [2.0]
improve = 300
maps = ["course:rotorpy/pillar"]
controllers = ["cascade", "se3"]
planners = ["rrtstar", "{PLANNER}"]
winds = [[0.1, 0.05, 0]]
"""
#: Two controllers flying the same trajectories, calm: the same PD law with stiff gains
#: and with soft ones, which lag and come within the goal tolerance about half a second
#: later in every mission (both reach the goal).
STIFF, SOFT = (f"plain_controller.py:PDAttitude(kp={kp}, kd={kd})"
               for kp, kd in ((6.5, 4.0), (1.0, 1.0)))
DUO_SPEC = f"""\
seeds = 3
speeds = [2.0]
improve = 300
control_rate = 250.0
maps = ["window:size=4x6x3,walls=1"]
controllers = ["{STIFF}", "{SOFT}"]
"""
#: z of a two-sided 95 % normal interval.
Z95 = 1.959963984540054


@pytest.fixture(scope="module")
def batch(tmp_path_factory) -> tuple[Path, str]:
    """The batch flown by ``quadnav batch`` into a folder; its folder and stdout."""
    folder = tmp_path_factory.mktemp("compare")
    shutil.copy(EXAMPLES / "plain_planner.py", folder)
    (folder / "spec.toml").write_text(SPEC)
    result = run_here("batch", folder / "spec.toml", "--quiet", "--workers", "1",
                      "-o", folder / "out")
    assert result.returncode == 0, result.stderr
    return folder / "out", result.stdout


@pytest.fixture(scope="module")
def duo(tmp_path_factory) -> Path:
    """The batch of :data:`DUO_SPEC` flown by ``quadnav batch``: its folder."""
    folder = tmp_path_factory.mktemp("duo")
    shutil.copy(EXAMPLES / "plain_controller.py", folder)
    (folder / "spec.toml").write_text(DUO_SPEC)
    result = run_here("batch", folder / "spec.toml", "--quiet", "--workers", "1",
                      "-o", folder / "out")
    assert result.returncode == 0, result.stderr
    return folder / "out"


def _rows(folder: Path) -> list[dict]:
    """results.csv read with the csv module alone."""
    with open(folder / "results.csv", newline="") as file:
        return list(csv.DictReader(file))


def _number(text: str) -> float | None:
    return float(text) if text else None


def _wilson(k: int, n: int) -> tuple[float, float]:
    """The Wilson score interval by its closed formula."""
    p, z2 = k / n, Z95 * Z95
    centre = (p + z2 / (2 * n)) / (1 + z2 / n)
    half = Z95 * math.sqrt(p * (1 - p) / n + z2 / (4 * n * n)) / (1 + z2 / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def _two_sided_binomial(k: int, n: int) -> float:
    """Exact two-sided p-value of k of n at one half, by counting outcomes."""
    tail = sum(math.comb(n, j) for j in range(min(k, n - k) + 1)) / 2 ** n
    return min(1.0, 2 * tail)


def _compare(folder: Path, *by: str) -> tuple[dict, list[dict], str]:
    """``quadnav compare`` run on ``folder``: compare.json, compare.csv's rows, stdout."""
    result = run_here("compare", folder, *(("--by", *by) if by else ()))
    assert result.returncode == 0, result.stderr
    with open(folder / "compare.csv", newline="") as file:
        table = list(csv.DictReader(file))
    return json.loads((folder / "compare.json").read_text()), table, result.stdout


@pytest.fixture(scope="module")
def compared(batch, tmp_path_factory) -> tuple[Path, dict, list[dict], str]:
    """``quadnav compare`` run once, by both axes (each pair of values contends), on a copy
    of the batch's folder that no test writes into: the copy, compare.json, compare.csv's
    rows and stdout."""
    out = tmp_path_factory.mktemp("compared") / "out"
    shutil.copytree(batch[0], out)
    return out, *_compare(out)


def test_the_batch_says_the_success_rate_of_each_contender(batch):
    out, stdout = batch
    planner = PLANNER
    assert f"per controller, planner (quadnav compare {out} draws the leaderboard):" in stdout
    for line in ("  cascade, rrtstar: 4 of 4, 100.0 % (51.0 to 100.0 %)",
                 "  se3, rrtstar: 0 of 4, 0.0 % (0.0 to 49.0 %)",
                 f"  cascade, {planner}: 4 of 4, 100.0 % (51.0 to 100.0 %)",
                 f"  se3, {planner}: 0 of 4, 0.0 % (0.0 to 49.0 %)"):
        assert line in stdout.splitlines()
    # the summary groups by them too: one group, and one heat-map panel, per pair
    groups = json.loads((out / "summary.json").read_text())["groups"]
    assert sorted((g["controller"], Path(g["planner"]).name) for g in groups) == [
        ("cascade", planner), ("cascade", "rrtstar"), ("se3", planner), ("se3", "rrtstar")]
    assert [g["successes"] for g in groups] == [4, 0, 4, 0]
    page = (out / "summary.html").read_text()
    assert f"{planner}, se3" in page


def test_each_contender_has_its_wilson_interval_and_medians_of_its_rows(compared):
    out, result, table, stdout = compared

    assert result["by"] == ["controller", "planner"]
    assert "compared by controller, planner: 4 contenders, 16 missions;" in stdout
    rows = _rows(out)
    assert len(table) == 4
    for entry in table:
        controller, planner = entry["contender"].split(", ")
        mine = [r for r in rows if r["controller"] == controller
                and Path(r["planner"].partition(":")[0]).name in planner]
        k, n = sum(r["success"] == "true" for r in mine), len(mine)
        assert (int(entry["successes"]), int(entry["n"])) == (k, n) == (
            (4, 4) if controller == "cascade" else (0, 4))
        low, high = _wilson(k, n)
        assert float(entry["ci_low"]) == pytest.approx(low, abs=1e-12)
        assert float(entry["ci_high"]) == pytest.approx(high, abs=1e-12)
        errors = [100 * float(r["rms_tracking_error_m"]) for r in mine]
        assert float(entry["tracking_error_median"]) == pytest.approx(statistics.median(errors))
        energy = [float(r["rotor_energy_j"]) for r in mine]
        assert float(entry["energy_q1"]) == pytest.approx(np.percentile(energy, 25))
    # best first: the cascade's two, then the SE(3) controller's
    assert [e["contender"].split(", ")[0] for e in table] == ["cascade"] * 2 + ["se3"] * 2
    assert [int(e["rank"]) for e in table] == [1, 2, 3, 4]


def test_paired_differences_are_tested_by_mcnemar_and_signed_ranks_with_holm(batch):
    out, _ = batch
    result, table, stdout = _compare(out, "controller")

    rows = _rows(out)
    assert [e["contender"] for e in table] == ["cascade", "se3"]
    assert [c["values"] for c in result["contenders"]] == [{"controller": "cascade"},
                                                           {"controller": "se3"}]
    # pairs: the same planner and seed, the controller differing
    by_pair = {}
    for row in rows:
        by_pair.setdefault((row["planner"], row["seed"]), {})[row["controller"]] = row
    assert len(by_pair) == 8
    only_cascade = sum(p["cascade"]["success"] == "true" and p["se3"]["success"] != "true"
                       for p in by_pair.values())
    only_se3 = sum(p["se3"]["success"] == "true" and p["cascade"]["success"] != "true"
                   for p in by_pair.values())
    tests = result["comparisons"]
    assert len(tests) == 6 and result["alpha"] == 0.05
    success = next(t for t in tests if t["metric"] == "success")
    assert (success["a_only"], success["b_only"], success["pairs"]) == (only_cascade, only_se3, 8)
    assert success["p"] == pytest.approx(_two_sided_binomial(only_cascade,
                                                             only_cascade + only_se3))
    # the SE(3) controller tracks worse in every pair: the signed-rank test's least p-value,
    # 2 / 2^8
    error = {name: [float(p[name]["rms_tracking_error_m"]) for p in by_pair.values()]
             for name in ("cascade", "se3")}
    assert all(a < b for a, b in zip(error["cascade"], error["se3"], strict=True))
    tracking = next(t for t in tests if t["metric"] == "tracking_error")
    assert tracking["p"] == pytest.approx(2 / 2 ** 8)
    # the SE(3) controller never reached the goal: no pair has two times to goal, so that
    # comparison tests nothing and stays out of the correction
    untested = next(t for t in tests if t["metric"] == "time_to_goal")
    assert untested["pairs"] == 0 and untested["p_holm"] == 1.0 and not untested["significant"]
    tested = [t for t in tests if t is not untested]
    assert all(t["pairs"] == 8 for t in tested)
    # Holm, step by step: the k-th smallest of m times m - k + 1, kept non-decreasing
    order = sorted(range(len(tested)), key=lambda i: tested[i]["p"])
    running = 0.0
    for k, i in enumerate(order):
        running = max(running, min(1.0, (len(tested) - k) * tested[i]["p"]))
        assert tested[i]["p_holm"] == pytest.approx(running)
        assert tested[i]["significant"] == (running < 0.05)
    assert success["significant"] and success["better"] == "cascade"
    assert tracking["significant"] and tracking["better"] == "cascade"
    assert "Holm-corrected over 5 tests" in stdout
    assert ("  cascade vs se3: success: 8 pairs only cascade reached the goal, 0 only se3; "
            "cascade better (p 0.0078, Holm 0.039)") in stdout.splitlines()


def test_batch_compare_draws_the_same_leaderboard_once_the_batch_is_done(batch):
    out, _ = batch
    result, _, stdout = _compare(out)
    (out / "compare.json").unlink()

    again = run_here("batch", out.parent / "spec.toml", "--quiet", "--compare", "-o", out)

    assert again.returncode == 0, again.stderr
    lines = again.stdout.splitlines()
    assert lines[0] == f"16 missions, all already in {out}"
    assert lines[-len(stdout.splitlines()):] == stdout.splitlines()
    assert json.loads((out / "compare.json").read_text())["contenders"] == result["contenders"]


def test_the_time_to_goal_is_each_flight_s_own_where_the_controllers_fly_one_trajectory(duo):
    result, table, stdout = _compare(duo, "controller")

    rows = _rows(duo)
    times = {name: [float(r["time_to_goal_s"]) for r in rows if r["controller"].endswith(name)]
             for name in (STIFF, SOFT)}
    durations = {name: [r["trajectory_duration_s"] for r in rows if r["controller"].endswith(name)]
                 for name in (STIFF, SOFT)}
    assert durations[STIFF] == durations[SOFT]  # one trajectory per seed for both
    # the soft gains lag: each flight of theirs comes within the tolerance later
    assert all(soft > stiff + 0.3 for stiff, soft in zip(times[STIFF], times[SOFT], strict=True))
    for entry in table:
        mine = times[entry["contender"]]
        assert float(entry["time_to_goal_median"]) == pytest.approx(statistics.median(mine))
        assert float(entry["time_to_goal_q1"]) == pytest.approx(np.percentile(mine, 25))
        assert int(entry["time_to_goal_n"]) == 3
    paired = next(c for c in result["comparisons"] if c["metric"] == "time_to_goal")
    ahead = 1 if paired["a"] == SOFT else -1
    assert paired["pairs"] == 3 and ahead * paired["median_difference"] > 0.3
    assert "untimed" in result and result["untimed"] == 0
    assert "before quadnav measured it" not in stdout
    page = (duo / "compare.html").read_text()
    assert "when the flight came within the goal tolerance to stay" in page
    assert f"{statistics.median(times[SOFT]):.3g} [" in page


def test_a_batch_written_before_the_time_to_goal_says_it_has_none(duo, tmp_path):
    old = tmp_path / "old"
    shutil.copytree(duo, old)
    with open(old / "results.csv", newline="") as file:
        rows = list(csv.DictReader(file))
    with open(old / "results.csv", "w", newline="") as file:
        writer = csv.DictWriter(file, UNTIMED_NAMES, extrasaction="ignore", lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    record = json.loads((old / "batch.json").read_text())
    (old / "batch.json").write_text(json.dumps(record | {"columns": list(UNTIMED_NAMES)}))

    result, table, stdout = _compare(old, "controller")

    note = ("time to goal: 6 missions reached the goal in rows written before quadnav "
            "measured it and have none; the time to goal is over the others")
    assert stdout.splitlines()[1] == note and result["untimed"] == 6
    assert all(entry["time_to_goal_n"] == "0" for entry in table)
    assert [line.count("—") for line in stdout.splitlines()[3:5]] == [1, 1]
    assert f"<p>{note}.</p>" in (old / "compare.html").read_text()
    paired = next(c for c in result["comparisons"] if c["metric"] == "time_to_goal")
    assert paired["pairs"] == 0 and paired["p_holm"] == 1.0 and not paired["significant"]
    # it tests nothing, so the correction is over the others alone
    others = [c for c in result["comparisons"] if c is not paired]
    assert all(c["pairs"] for c in others)
    assert [c["p_holm"] for c in others] == pytest.approx(holm([c["p"] for c in others]))
    assert f"Holm-corrected over {len(others)} tests" in stdout


def test_two_plugins_of_files_with_the_same_name_are_two_contenders_named_in_full(batch):
    out, _ = batch
    rows = read_rows(out / "results.csv")
    for row in rows:  # the same file name in two folders
        if row["planner"] != "rrtstar":
            row["planner"] = f"/a/{PLANNER}" if row["seed"] % 2 else f"/b/{PLANNER}"

    result = compare(rows, ["planner"])

    # each at a rate of one half, the one of 8 missions first (its interval is narrower)
    assert [(c["contender"], c["n"], c["successes"]) for c in result["contenders"]] == [
        ("rrtstar", 8, 4), (f"/a/{PLANNER}", 4, 2), (f"/b/{PLANNER}", 4, 2)]


def test_holm_adjusts_a_textbook_example():
    assert holm([0.01, 0.04, 0.03, 0.005]) == pytest.approx([0.03, 0.06, 0.06, 0.02])
    assert holm([0.5, 0.9]) == pytest.approx([1.0, 1.0])


def test_mcnemar_counts_the_discordant_pairs_and_equal_pairs_carry_no_signed_rank():
    first = [True, True, True, False, False, True, True]
    second = [False, False, True, True, False, False, False]
    found = mcnemar(first, second)
    assert (found["a_only"], found["b_only"]) == (4, 1)
    assert found["p"] == pytest.approx(_two_sided_binomial(4, 5)) == pytest.approx(12 / 32)
    assert mcnemar([True, False], [True, False])["p"] == 1.0
    assert signed_rank([1.0, 2.0, 3.0], [1.0, 2.0, 3.0]) == 1.0
    # five differences of one sign: the exact two-sided p-value 2 / 2^5
    assert signed_rank([1.0, 2.0, 3.0, 4.0, 5.5], [0.5, 1.0, 1.0, 1.0, 1.0]) == pytest.approx(
        2 / 2 ** 5)


def test_the_page_and_figure_show_every_contender(compared):
    out, result, table, stdout = compared

    assert stdout.splitlines()[-1] == (f"wrote {out}/compare.csv, {out}/compare.json, "
                                       f"{out}/compare.html, {out}/compare.png")
    page = (out / "compare.html").read_text()
    assert "http://" not in page and "https://" not in page
    assert page.count('src="data:image/png;base64,') == 1
    assert "alpha = 0.05" in page and "Holm" in page and "McNemar" in page
    for entry in table:
        assert f"<td>{breakable(entry['contender'])}</td>" in page
    png = (out / "compare.png").read_bytes()
    assert png.startswith(b"\x89PNG")
    fig = leaderboard_figure(result)
    FigureCanvasAgg(fig)
    assert_labels_apart(fig, min_ticks=1)
    assert_texts_off_other_axes(fig)


@pytest.mark.parametrize("window_width", [1280, 960])
def test_in_chromium_the_page_fits_and_shows_the_bars(browser, compared, tmp_path,
                                                     window_width):
    out = compared[0]
    browser.set_window_size(window_width, 900)
    try:
        browser.get((out / "compare.html").as_uri())
        width = browser.execute_script("return document.documentElement.scrollWidth")
        assert width <= browser.execute_script("return window.innerWidth"), width
        image = browser.find_element("css selector", "figure img")
        assert browser.execute_script("return arguments[0].complete && "
                                      "arguments[0].naturalWidth > 0", image)
        assert 0 < image.size["width"] <= window_width
        rows = browser.find_elements("css selector", "table")[0].find_elements(
            "css selector", "tbody tr")
        assert len(rows) == 4
        height = browser.execute_script("return document.documentElement.scrollHeight")
        browser.set_window_size(window_width, min(height + 200, 16_000))
        browser.save_screenshot(str(tmp_path / "compare.png"))
        shot = np.asarray(Image.open(io.BytesIO(image.screenshot_as_png)).convert("RGB"),
                          dtype=int)
        red, green, blue = shot[..., 0], shot[..., 1], shot[..., 2]
        assert ((green > red + 40) & (green > blue + 40)).sum() > 500  # the success bars
        assert ((blue > red + 40) & (blue > 120)).sum() > 500  # the medians' bars
        assert (shot.sum(axis=2) < 200).sum() > 500  # text and whiskers
    finally:
        browser.set_window_size(1280, 860)


def test_a_folder_that_is_not_a_batch_is_refused(tmp_path):
    assert_user_error(run_here("compare", tmp_path), f"{tmp_path}: not a quadnav batch folder",
                      "expected the -o DIR of quadnav batch")
    assert_user_error(run_here("compare", tmp_path / "nowhere"),
                      f"{tmp_path / 'nowhere'}: not a quadnav batch folder")
    assert not list(tmp_path.iterdir())


def test_a_batch_without_a_finished_mission_is_refused(batch, tmp_path):
    out, _ = batch
    (tmp_path / "batch.json").write_bytes((out / "batch.json").read_bytes())
    assert_user_error(run_here("compare", tmp_path),
                      f"{tmp_path}: the batch has no finished mission yet; run it first")
    (tmp_path / "results.csv").write_text((out / "results.csv").read_text().splitlines()[0]
                                          + "\n")
    assert_user_error(run_here("compare", tmp_path),
                      f"{tmp_path}: the batch has no finished mission yet; run it first")


def test_a_batch_with_a_single_contender_or_an_axis_that_does_not_vary_is_refused(batch,
                                                                                  tmp_path):
    out, _ = batch
    result = run_here("batch", "window:size=4x6x3,walls=1", "--seeds", "1", "--quiet",
                      "-o", tmp_path / "one")
    assert result.returncode == 0, result.stderr
    # one mission, one job: one worker started, not one per CPU
    assert json.loads((tmp_path / "one" / "summary.json").read_text())["ran_on"]["workers"] == 1

    assert_user_error(run_here("compare", tmp_path / "one"),
                      f"{tmp_path / 'one'}: the batch has a single contender",
                      "expected a batch over two or more of them")
    assert_user_error(run_here("compare", out, "--by", "wind"),
                      f"--by wind: every mission of {out} flies wind (0.1, 0.05, 0) N; "
                      "expected an axis that varies: controller, planner")
    assert not (tmp_path / "one" / "compare.json").exists()
