"""``quadnav grade``: a submission's own parts flown on a course's maps and seeds (rotorpy's
worlds, shipped with quadnav), each mission into a run folder, with the grade a TA hands
back. A good submission (the examples' plain-Python controller and planner, copied) passes;
a faulty one (a planner through a block, a controller that raises, wrong keys) fails the
right missions with the right reason and its own traceback, never crashing the grader;
bad grader input is one line and exit 2; an interrupted or repeated grade keeps the
missions finished."""

from __future__ import annotations

import csv
import json
import re
import shutil
import signal
import subprocess
import time
from pathlib import Path

import pytest
from clitools import QUADNAV, run_here

from quadnav.batch.executor import RETRIES

#: One worker for the module, so that its module-scoped fixtures are built once under
#: --dist loadgroup (each test apart would build them on each worker).
pytestmark = pytest.mark.xdist_group("grade")

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
#: Two shipped course maps with their queries; a cheap search budget for the baseline, and
#: the plain-Python controllers run at 250 Hz (a quarter of the steps of 1 kHz's).
COURSE = """
seeds = {seeds}

[parts]
controller = "controller.py:{controller}"
planner = "planner.py:{planner}"

[[maps]]
map = "course:rotorpy/double_pillar"
start = [-1.1, -3, 1]
goal = [-1.1, 3, 1.5]

[[maps]]
map = "course:meam620/grid_forest"
start = [1.25, 1.25, 1]
goal = [3.25, 5.25, 1.5]

[mission]
planner = {{improve = 300}}
simulation = {{control_rate = 250.0}}
"""
#: A student's planner that imports a file of the submission by module name: the straight
#: line on the map of two pillars (through one of them), else the example's graph search.
PLANNER = """
import os
import signal
import time

import numpy as np
from search_{tag} import graph_search


def straight_on_pillars(world, start, goal, margin):
    if len(world.blocks) == 2:
        return np.array([start, goal])
    return graph_search(world, start, goal, margin, resolution=0.5)


def search(world, start, goal, margin):
    return graph_search(world, start, goal, margin, resolution=0.5)


def stuck_in_the_forest(world, start, goal, margin):
    while len(world.blocks) != 2:  # until the grade is stopped
        time.sleep(0.05)
    return search(world, start, goal, margin)


def killed_on_pillars(world, start, goal, margin):
    if len(world.blocks) == 2:  # as a crash in compiled code or the OOM killer would
        os.kill(os.getpid(), signal.SIGKILL)
    return search(world, start, goal, margin)
"""
#: A student's controllers: the example's PD law, one that raises after 0.5 s, one that
#: returns keys of no control abstraction.
CONTROLLER = """
import sys

from pd_{tag} import PDAttitude


class Good(PDAttitude):
    pass


class Raises(PDAttitude):
    def update(self, t, state, flat_output):
        if t > 0.5:
            return self.thrust_over(0.0)
        return super().update(t, state, flat_output)

    def thrust_over(self, tilt):
        return {{"cmd_thrust": self.mass * 9.81 / tilt, "cmd_q": [0, 0, 0, 1]}}


class Biased(PDAttitude):
    # flies 6 cm off the reference along x and along y

    def update(self, t, state, flat_output):
        aim = flat_output | {{"x": flat_output["x"] + [0.06, 0.06, 0.0]}}
        return super().update(t, state, aim)


class Sinking(PDAttitude):
    def update(self, t, state, flat_output):
        aim = flat_output | {{"x": flat_output["x"] - [0.0, 0.0, 3.0]}}
        return super().update(t, state, aim)


class Quits(PDAttitude):
    def update(self, t, state, flat_output):
        sys.exit("debugging")


class WrongKeys(PDAttitude):
    def update(self, t, state, flat_output):
        return {{"thrust": 1.0}}
"""


#: The flags that grade a course on its first map alone, double_pillar, with its query.
PILLAR_ONLY = ["--maps", "course:rotorpy/double_pillar", "--start", "-1.1", "-3", "1",
               "--goal", "-1.1", "3", "1.5"]
#: The flags that grade a course on its second map alone, grid_forest, with its query.
FOREST_ONLY = ["--maps", "course:meam620/grid_forest", "--start", "1.25", "1.25", "1",
               "--goal", "3.25", "5.25", "1.5"]


def submission(folder: Path, tag: str) -> Path:
    """A submission folder: the examples' files (under names of its own: a process keeps
    modules by name) and the student's planner and controllers."""
    folder.mkdir()
    shutil.copy(EXAMPLES / "plain_planner.py", folder / f"search_{tag}.py")
    shutil.copy(EXAMPLES / "plain_controller.py", folder / f"pd_{tag}.py")
    (folder / "planner.py").write_text(PLANNER.format(tag=tag))
    (folder / "controller.py").write_text(CONTROLLER.format(tag=tag))
    return folder


def course(folder: Path, seeds: int, controller: str, planner: str) -> Path:
    path = folder / "grade.toml"
    path.write_text(COURSE.format(seeds=seeds, controller=controller, planner=planner))
    return path


def grade_json(folder: Path) -> dict:
    return json.loads((folder / "grade.json").read_text())


def test_a_good_submission_passes_every_mission(tmp_path):
    # one seed: nothing of the submission's missions is seeded (its planner is a graph
    # search, the flights have no gusts or noise), so another seed would fly the same flights
    student = submission(tmp_path / "alice", "good")
    spec = course(tmp_path, 1, "Good", "search")
    result = run_here("grade", student, "--course", spec, "--no-baseline", "--workers", "2",
                      "-o", tmp_path / "out")
    assert result.returncode == 0, result.stderr
    assert "score: 2 of 2 missions passed" in result.stdout
    grade = grade_json(tmp_path / "out")
    assert grade["score"] == {"passed": 2, "graded": 2, "total": 2}
    assert grade["complete"] and grade["baseline"] is None
    assert [(m["label"], m["seed"]) for m in grade["missions"]] == [
        ("rotorpy-double_pillar", 0), ("meam620-grid_forest", 0)]
    for mission in grade["missions"]:
        row = mission["submission"]
        assert row["passed"] and row["outcome"] == "passed" and row["reason"] == ""
        numbers = row["metrics"]
        assert (0.5 * numbers["trajectory_duration_s"] < numbers["time_to_goal_s"]
                < numbers["flight_time_s"])
        assert row["parts"]["controller.name"] == f"{student / 'controller.py'}:Good"
        run = tmp_path / "out" / row["folder"]
        metrics = json.loads((run / "metrics.json").read_text())
        assert metrics["success"] and metrics["planner"].endswith("planner.py:search")
        assert (run / "flight_3d.png").is_file() and (run / "report.html").is_file()
        assert 'name = "' + str(student / "controller.py") + ':Good"' in (
            run / "mission.toml").read_text()
    lines = list(csv.DictReader((tmp_path / "out" / "grade.csv").open()))
    assert [line["passed"] for line in lines] == ["True"] * 2
    page = (tmp_path / "out" / "grade.html").read_text()
    assert "<b>2 of 2</b> missions passed" in page and "Failed missions" not in page


@pytest.fixture(scope="module")
def faulty(tmp_path_factory):
    """A faulty submission graded with the baseline: its planner goes through a pillar on
    double_pillar, its controller raises on grid_forest."""
    root = tmp_path_factory.mktemp("grade")
    student = submission(root / "bob", "faulty")
    spec = course(root, 1, "Raises", "straight_on_pillars")
    result = run_here("grade", student, "--course", spec, "-o", root / "out")
    return root, student, spec, result


def test_a_faulty_submission_fails_the_right_missions_for_the_right_reason(faulty):
    root, _, _, result = faulty
    assert result.returncode == 1, result.stderr
    assert "score: 0 of 2 missions passed (quadnav's own parts: 2 of 2)" in result.stdout
    grade = grade_json(root / "out")
    pillars, forest = (m["submission"] for m in grade["missions"])
    assert pillars["outcome"] == "no path"
    assert pillars["reason"].startswith(
        "no path: planner planner.py:straight_on_pillars returned a path whose segment 0 "
        "from (-1.1, -3, 1) to (-1.1, 3, 1.5) passes through block 0 ")
    assert forest["outcome"] == "part error"
    assert forest["reason"].startswith("controller controller.py:Raises: update(0.5")
    assert forest["reason"].endswith("raised ZeroDivisionError: float division by zero")
    trace = forest["traceback"]
    assert 'File "controller.py", line ' in trace and "in thrust_over" in trace
    assert "quadnav" not in trace  # the student's frames only
    error = (root / "out" / forest["folder"] / "error.txt").read_text()
    assert "in thrust_over" in error and "ZeroDivisionError" in error
    for mission in grade["missions"]:  # quadnav's own parts fly the same missions
        assert mission["baseline"]["passed"], mission["baseline"]["reason"]
        assert mission["baseline"]["metrics"]["rms_tracking_error_m"] < 0.05


def test_the_page_shows_the_score_the_rule_and_each_failure_with_its_flight(faulty):
    root = faulty[0]
    page = (root / "out" / "grade.html").read_text()
    assert "<b>0 of 2</b> missions passed" in page
    assert "with no contact with a block or the floor and the vehicle&#39;s body inside" in page
    assert page.count('<td class="fail">') == 4  # the map x seed table and the list
    assert page.count('<td class="pass">pass</td>') == 2  # the baseline, beside them
    assert "passes through block 0" in page and "in thrust_over" in page
    # the pillar mission's figure (its refused path) is embedded; the controller's
    # mission never flew, so it has none
    assert page.count("data:image/png;base64,") == 1
    assert 'href="missions/submission/rotorpy-double_pillar/seed-0/report.html"' in page


def test_the_page_reads_in_a_browser(faulty, browser):
    page = faulty[0] / "out" / "grade.html"
    browser.get(page.as_uri())
    assert browser.title == "Grade of bob"
    sizes = browser.execute_script(
        "return Array.from(document.images).map(i => i.complete && i.naturalWidth)")
    assert sizes and all(sizes)
    assert not [entry for entry in browser.get_log("browser") if entry["level"] == "SEVERE"]


def test_a_grade_again_flies_only_what_changed(faulty, tmp_path):
    root, student, spec, _ = faulty
    out = tmp_path / "out"
    shutil.copytree(root / "out", out)
    again = run_here("grade", student, "--course", spec, "-o", out)
    assert again.returncode == 1
    assert "0 to fly, 4 kept from an earlier grade" in again.stdout
    # a resubmission: the submission's missions fly again, the baseline's are kept; its
    # planner finds the path on the pillars too, its controller raises at once (so that
    # each row is seen to be the new files', a mission failing at its first step)
    changed = tmp_path / "carol"
    shutil.copytree(student, changed)
    (changed / "controller.py").write_text(
        (student / "controller.py").read_text().replace("if t > 0.5:", "if t >= 0:"))
    (changed / "planner.py").write_text(
        (student / "planner.py").read_text().replace("== 2", "== -1"))
    result = run_here("grade", changed, "--course", spec, "-o", out)
    assert "2 to fly, 2 kept from an earlier grade" in result.stdout
    assert result.returncode == 1
    grade = grade_json(out)
    for mission in grade["missions"]:
        row = mission["submission"]
        assert row["outcome"] == "part error"
        assert row["reason"].startswith("controller controller.py:Raises: update(0, state, ")


def test_strict_grading_fails_a_flight_that_kept_less_margin(tmp_path):
    student = submission(tmp_path / "fay", "strict")
    spec = course(tmp_path, 1, "Biased", "search")
    pillars = [*PILLAR_ONLY, "--no-baseline", "-o", tmp_path / "out"]
    lenient = run_here("grade", student, "--course", spec, *pillars)
    assert lenient.returncode == 0, lenient.stdout
    row = grade_json(tmp_path / "out")["missions"][0]["submission"]
    assert row["passed"] and 0.05 < row["metrics"]["margin_shortfall_m"] < 0.07
    strict = run_here("grade", student, "--course", spec, *pillars, "--strict")
    assert strict.returncode == 1
    assert "1 to fly, 0 kept" in strict.stdout  # graded by another rule: flown again
    grade = grade_json(tmp_path / "out")
    row = grade["missions"][0]["submission"]
    assert row["outcome"] == "margin"
    assert re.fullmatch(r"kept 0\.1\d\d m of the 0\.2 m margin asked off the legs, least at "
                        r"t = \d+\.\d\d s", row["reason"]), row["reason"]
    assert grade["strict"] and "fly --strict" in grade["rule"]


def test_a_stopped_grade_keeps_the_missions_finished(tmp_path):
    student = submission(tmp_path / "gus", "stopped")
    spec = course(tmp_path, 1, "Good", "stuck_in_the_forest")
    out = tmp_path / "out"
    command = [*QUADNAV, "grade", student, "--course", spec, "--no-baseline", "-o", out]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True)
    first = out / "missions/submission/rotorpy-double_pillar/seed-0/grade-result.json"
    waited = 0
    while not first.exists() and process.poll() is None and waited < 2400:
        time.sleep(0.05)
        waited += 1
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130, err
    assert err.startswith("quadnav: stopped: kept 1 of 2 missions"), err
    grade = grade_json(out)
    assert not grade["complete"] and grade["score"] == {"passed": 1, "graded": 1, "total": 2}
    assert "stopped before every mission flew" in (out / "grade.html").read_text()
    again = run_here("grade", student, "--course", spec, "--no-baseline", *PILLAR_ONLY,
                     "-o", out)
    assert again.returncode == 0 and "0 to fly, 1 kept from an earlier grade" in again.stdout


def test_a_crash_fails_its_mission_saying_where_and_when(tmp_path):
    student = submission(tmp_path / "hal", "crash")
    spec = course(tmp_path, 1, "Sinking", "search")
    result = run_here("grade", student, "--course", spec, *PILLAR_ONLY, "--no-baseline",
                      "-o", tmp_path / "out")
    assert result.returncode == 1
    row = grade_json(tmp_path / "out")["missions"][0]["submission"]
    assert row["outcome"] == "crashed", row["reason"]
    assert re.fullmatch(r"hit the floor at \d+\.\d\d m/s at t = \d+\.\d\d s", row["reason"])
    assert (tmp_path / "out" / row["figure"]).is_file()  # the flight down to the floor


def test_wrong_keys_fail_their_mission_with_the_line(tmp_path):
    student = submission(tmp_path / "dan", "keys")
    spec = course(tmp_path, 1, "WrongKeys", "search")
    result = run_here("grade", student, "--course", spec, *PILLAR_ONLY, "--no-baseline",
                      "-o", tmp_path / "out")
    assert result.returncode == 1
    row = grade_json(tmp_path / "out")["missions"][0]["submission"]
    assert row["outcome"] == "part error" and row["traceback"] is None
    assert row["reason"] == ("controller controller.py:WrongKeys: update(0, state, "
                             "flat_output) returned no cmd_thrust or cmd_q (it gave thrust): "
                             "flying by cmd_ctatt, expected cmd_thrust and cmd_q")


def test_a_part_that_calls_exit_fails_its_mission_not_the_grader(tmp_path):
    student = submission(tmp_path / "ivy", "quits")
    spec = course(tmp_path, 2, "Quits", "search")
    result = run_here("grade", student, "--course", spec, "--no-baseline", "-o",
                      tmp_path / "out")
    assert result.returncode == 1, result.stderr
    assert "score: 0 of 4 missions passed" in result.stdout
    grade = grade_json(tmp_path / "out")
    # each mission in its place, map by map, seed by seed
    assert [(m["label"], m["seed"]) for m in grade["missions"]] == [
        ("rotorpy-double_pillar", 0), ("rotorpy-double_pillar", 1),
        ("meam620-grid_forest", 0), ("meam620-grid_forest", 1)]
    for mission in grade["missions"]:
        row = mission["submission"]
        assert row["outcome"] == "part error" and row["reason"] == "SystemExit: debugging"
        assert 'File "controller.py", line ' in row["traceback"]


def test_a_part_that_kills_its_process_fails_its_mission_and_the_grade_goes_on(tmp_path):
    # in a process of its own: a grader that flew the mission itself would be killed
    student = submission(tmp_path / "jay", "killed")
    spec = course(tmp_path, 1, "Good", "killed_on_pillars")
    out = tmp_path / "out"
    result = subprocess.run([*QUADNAV, "grade", student, "--course", spec, "--no-baseline",
                             "-o", out], capture_output=True, text=True, timeout=600)
    assert result.returncode == 1, result.stderr
    reason = f"its worker process died {RETRIES + 1} times (killed by SIGKILL); given up"
    assert f"  submission rotorpy-double_pillar/seed-0: FAIL (process died): {reason}\n" in (
        result.stdout)
    assert "score: 1 of 2 missions passed" in result.stdout
    grade = grade_json(out)
    assert grade["complete"]
    pillars, forest = (m["submission"] for m in grade["missions"])
    assert (pillars["outcome"], pillars["reason"]) == ("process died", reason)
    assert forest["passed"], forest["reason"]
    folder = out / pillars["folder"]
    assert (folder / "error.txt").read_text() == reason + "\n"
    assert not (folder / "grade-result.json").exists()  # a re-run flies it again
    assert reason in (out / "grade.html").read_text()


def test_a_mission_past_the_time_limit_is_stopped_and_fails(tmp_path):
    student = submission(tmp_path / "kim", "stuck")
    spec = course(tmp_path, 1, "Good", "stuck_in_the_forest")
    result = run_here("grade", student, "--course", spec, *FOREST_ONLY, "--no-baseline",
                      "--mission-time-limit", "3", "-o", tmp_path / "out")
    assert result.returncode == 1, result.stderr
    assert "score: 0 of 1 missions passed" in result.stdout
    grade = grade_json(tmp_path / "out")
    row = grade["missions"][0]["submission"]
    assert grade["complete"] and grade["course"]["mission_time_limit"] == 3
    assert (row["outcome"], row["reason"]) == ("time limit",
                                               "ran longer than the 3 s limit; stopped")


def test_a_missing_file_is_the_submissions_failure(tmp_path):
    student = tmp_path / "erin"
    student.mkdir()
    result = run_here("grade", student, "--maps", "forest:seed=3", "--seeds", "1",
                      "--controller", "se3_control.py:SE3Control", "--no-baseline",
                      "-o", tmp_path / "out")
    assert result.returncode == 1
    row = grade_json(tmp_path / "out")["missions"][0]["submission"]
    assert row["outcome"] == "part error"
    assert row["reason"] == ("the submission's controller: controller se3_control.py: "
                             "no such file")


@pytest.mark.parametrize(("setup", "args", "message"), [
    ("", ["nowhere", "--maps", "forest", "--controller", "c.py:C"],
     "nowhere: expected the submission's folder"),
    ("", [".", "--seeds", "1"], "the command line: no maps to grade on; give maps = [...] "
                                "in a course file (--course FILE) or --maps MAP ..."),
    ("", [".", "--maps", "forest"], "nothing of the submission to grade: name its parts "
                                    "([parts] in the course file, or --controller, --planner, "
                                    "--reference)"),
    ("", [".", "--maps", "forest", "--controller", "c.py:C(1)"],
     "--controller: controller 'c.py:C(1)': give its arguments by keyword, key=value"),
    ("", [".", "--controller", "c.py:C", "--start", "0", "0", "1"],
     "--start and --goal apply to the maps of --maps; give a course file's maps their own "
     "start and goal"),
    ("seeds = 0\nmaps = ['forest']\n", [".", "--course", "g.toml"],
     "g.toml:1: seeds: expected a whole number from 1 to 1,000, got 0"),
    ("maps = ['forest']\nsped = 3\n", [".", "--course", "g.toml"],
     "g.toml:2: sped: unknown key; expected one of maps, seeds, strict, baseline, "
     "mission_time_limit, parts, mission"),
    ("maps = ['forest']\nmission_time_limit = 'long'\n", [".", "--course", "g.toml"],
     "g.toml:2: mission_time_limit: expected from 0 to 86,400 s, got 'long'"),
    ("maps = ['forest']\n[mission]\nmap = 'window'\n", [".", "--course", "g.toml"],
     "g.toml:2: mission: map is set for each mission by the course's maps and seeds; give "
     "maps = [...] (with start, goal, margin) and seeds instead"),
    ("maps = ['forest']\n[mission.trajectory]\nspeed = -1\n", [".", "--course", "g.toml"],
     "g.toml:3: mission.trajectory.speed: expected from 0.01 to 100 m/s or \"max\", got -1"),
    ("[parts]\ncontroller = 'c.py:C'\n[[maps]]\nmap = 'course:rotorpy/pillar'\n"
     "start = [-0.9, 0, 1]\ngoal = [3, 3, 1]\n", [".", "--course", "g.toml"],
     "the course's map course:rotorpy/pillar (seed 0): start (-0.9, 0, 1): inside block 0 [-1, -0.75] x [-0.125, 0.125] x [-0.5, 3]; a path must "
     "start in free space"),
])
def test_bad_grader_input_is_one_line_and_exit_2(tmp_path, setup, args, message):
    if setup:
        (tmp_path / "g.toml").write_text(setup)
    result = run_here("grade", *args, "-o", "out", cwd=tmp_path)
    assert result.returncode == 2, result.stdout
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"quadnav: error: {message}"), lines
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("limit", ["-1", "long"])
def test_a_bad_time_limit_is_one_line_and_exit_2(tmp_path, limit):
    result = run_here("grade", ".", "--maps", "forest", "--controller", "c.py:C",
                      "--mission-time-limit", limit, "-o", "out", cwd=tmp_path)
    assert result.returncode == 2, result.stdout
    assert result.stderr.splitlines() == [
        "quadnav grade: error: argument --mission-time-limit: expected from 0 to 86,400 s, "
        f"got '{limit}' (see quadnav grade --help)"]
    assert not (tmp_path / "out").exists()
