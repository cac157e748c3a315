"""quadnav tune: the search space, the objective, a real SQLite Optuna study that resumes,
the same study on one worker and on a real local Ray, tuned gains that beat the vehicle's
own and every course table on flights they were not tuned on, and bad input."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import optuna
import pytest
from clitools import assert_user_error, run_here

from quadnav.config import as_plain
from quadnav.control.gains import Gains, course_gain_names
from quadnav.control.registry import controller_gains
from quadnav.errors import QuadnavError
from quadnav.tune.evaluate import item_cost
from quadnav.tune.run import TuneRun, TuneSettings
from quadnav.tune.space import CASCADE, OUTER, starting_point, with_values
from quadnav.tune.study import StudySettings, distributions, open_study
from quadnav.vehicle.params import load_params

TRAINING = """references = ["hover:duration=3", "step:axis=x,size=1,duration=4",
              "helix:radius=1,speed=1.5,laps=1"]
maps = ["window:size=6x8x3,walls=1"]
seeds = [0]
speeds = [2.0]
gusts = [0.01]
"""
HELD_OUT = """references = ["circle:radius=1,speed=2", "step:axis=y,size=1,duration=4"]
maps = ["forest:size=8x8x4,seed=3"]
seeds = [5]
speeds = [2.5]
gusts = [0.01]
"""
#: Only references: a study over them flies in a fraction of a second per trial.
QUICK = """references = ["hover:duration=2", "step:axis=z,size=0.5,duration=3"]
gusts = [0.01]
"""


def _sets(folder, training=TRAINING, held_out=HELD_OUT):
    (folder / "train.toml").write_text(training)
    (folder / "test.toml").write_text(held_out)
    return ["--train", folder / "train.toml", "--test", folder / "test.toml"]


def _trials(folder) -> list[list[str]]:
    with open(folder / "trials.csv", newline="") as file:
        return list(csv.reader(file))


# --- the space and the objective -----------------------------------------------------------


@pytest.mark.parametrize("preset", ["tello", "rbe595"])
def test_the_starting_point_is_the_vehicles_own_gains(preset):
    gains = controller_gains("cascade", load_params(preset))
    assert as_plain(with_values(gains, starting_point(gains, CASCADE))) == as_plain(gains)
    point = starting_point(gains, OUTER)
    assert set(point) == {f"{loop}.{gain}.{axes}" for loop in ("position", "velocity")
                          for gain in ("kp", "ki", "kd") for axes in ("xy", "z")}


def test_a_knob_sets_its_axes_together():
    gains = with_values(Gains(), {"velocity.kp.xy": 7.5, "attitude_kp.yaw": 3.0,
                                  "limits.tilt_max_deg": 33.0})
    assert gains.velocity.kp.tolist() == [7.5, 7.5, Gains().velocity.kp[2]]
    assert gains.attitude_kp.tolist() == [12.0, 12.0, 3.0]
    assert gains.limits.tilt_max_deg == 33.0


def test_the_cost_of_a_flight():
    clean = {"rms_tracking_error_m": 0.01, "overshoot_percent": None, "mixer_saturation": 0.0,
             "success": True}
    assert item_cost(clean) == pytest.approx(0.0)  # ln(1 cm / 1 cm)
    assert item_cost(clean | {"rms_tracking_error_m": 0.01 * math.e}) == pytest.approx(1.0)
    assert item_cost(clean | {"overshoot_percent": 4.0}) == pytest.approx(0.0)  # allowed
    assert item_cost(clean | {"overshoot_percent": 15.0}) == pytest.approx(2.0)
    assert item_cost(clean | {"mixer_saturation": 0.5}) == pytest.approx(1.0)
    assert item_cost(clean | {"success": False}) == pytest.approx(5.0)


# --- the study ------------------------------------------------------------------------------


def test_a_study_resumes_with_interrupted_trials_failed_and_refuses_other_knobs(tmp_path):
    settings = StudySettings(trials=3, sampler="tpe", seed=0, name="s", parallel=2,
                             storage=f"sqlite:///{tmp_path / 'study.db'}")
    start = starting_point(Gains(), OUTER)
    study = open_study(settings, OUTER, start)
    first = study.ask(distributions(OUTER))  # the enqueued starting point
    assert first.params == start
    study.tell(first, 1.0)
    study.ask(distributions(OUTER))  # asked, never told: the run was stopped here
    again = open_study(settings, OUTER, start)  # a new process opening the same storage
    states = [trial.state for trial in again.trials]
    assert states == [optuna.trial.TrialState.COMPLETE, optuna.trial.TrialState.FAIL]
    with pytest.raises(QuadnavError, match="searches other gains"):
        open_study(settings, CASCADE, starting_point(Gains(), CASCADE))


def _quick_run(folder, ray: bool) -> list[float]:
    (folder / "quick.toml").write_text(QUICK)
    settings = TuneSettings(
        vehicle="tello", gains=None, space="outer",
        study=StudySettings(trials=6, sampler="tpe", seed=3, name="quick", parallel=3,
                            storage=f"sqlite:///{folder / 'study.db'}"),
        training=str(folder / "quick.toml"), held_out=str(folder / "quick.toml"), compare=())
    tuning = TuneRun(settings)
    outcome = tuning.run(tuning.plan(), workers=1 if not ray else 2, ray=ray)
    return [trial.value for trial in outcome.trials]


def test_the_same_seed_gives_the_same_study_on_a_local_worker_and_on_ray(tmp_path):
    pytest.importorskip("ray")
    (tmp_path / "local").mkdir()
    (tmp_path / "ray").mkdir()
    local = _quick_run(tmp_path / "local", ray=False)
    on_ray = _quick_run(tmp_path / "ray", ray=True)
    assert len(local) == 6 and local == on_ray


# --- the command ----------------------------------------------------------------------------


def test_tuned_gains_beat_the_vehicles_own_and_every_course_table_held_out(tmp_path):
    out = tmp_path / "out"
    result = run_here("tune", *_sets(tmp_path), "--trials", "24", "--parallel", "4",
                      "--workers", "1", "--quiet", "-o", out)
    assert result.returncode == 0, result.stderr
    record = json.loads((out / "tune.json").read_text())
    print(result.stdout)
    held_out = record["scores"]["held-out"]
    assert set(held_out) == {"own", *course_gain_names(), "tuned"}
    tuned = held_out.pop("tuned")
    assert tuned["successes"] == tuned["flights"] == 3
    for name, scores in held_out.items():  # lower median RMS error at equal or better success
        assert tuned["successes"] >= scores["successes"], name
        assert tuned["median_rms_tracking_error_m"] < scores["median_rms_tracking_error_m"], name
    # gains.toml is the best trial's point, a whole gain set that flies as --gains.
    gains = controller_gains("cascade", load_params("tello"), out / "gains.toml")
    assert as_plain(gains) == as_plain(with_values(Gains(), record["best_params"]))
    assert record["best_objective"] <= record["scores"]["training"]["own"]["objective"]
    rows = _trials(out)
    assert rows[0][:2] == ["trial", "objective"] and len(rows) == 25
    assert float(rows[1][1]) == pytest.approx(record["scores"]["training"]["own"]["objective"])
    page = (out / "report.html").read_text()
    assert "http://" not in page and "https://" not in page and page.count("<img") == 2
    # The study is kept: asking for more trials resumes it, the first 24 as they were.
    resumed = run_here("tune", *_sets(tmp_path), "--trials", "28", "--parallel", "4",
                       "--workers", "1", "--quiet", "-o", out)
    assert resumed.returncode == 0, resumed.stderr
    again = _trials(out)
    assert len(again) == 29 and again[:25] == rows


@pytest.mark.parametrize(("extra", "set_text", "fragments"), [
    (["--trials", "0"], None, ["--trials", "expected a whole number from 1"]),
    (["--gains", "p2a-nope"], None, ["p2a-nope"]),
    (["--storage", "nosuch://x"], None, ["cannot open the study storage nosuch://x"]),
    ([], 'references = ["hover"]\ngains = ["a.toml"]\n', ["train.toml", "gains",
                                                         "takes no gains"]),
    ([], 'references = ["spiral"]\n', ["train.toml", "references", "spiral"]),
    ([], 'references = ["hover"]\nmaps = ["forest"]\nspeeds = [0]\n',
     ["train.toml", "speeds"]),
    ([], "seeds = [1]\n", ["train.toml", "expected references, maps or both"]),
])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, extra, set_text, fragments):
    sets = _sets(tmp_path, training=set_text or QUICK, held_out=QUICK)
    result = run_here("tune", *sets, *extra, "--trials", "1", "--quiet",
                      "-o", tmp_path / "out")
    assert_user_error(result, *fragments)
    assert not (tmp_path / "out").exists()


def test_the_tuned_gains_fly_a_mission(tmp_path):
    # The gains file a study writes is a --gains file for every command.
    gains = with_values(Gains(), {"velocity.kp.xy": 6.0, "position.kp.xy": 2.2})
    from quadnav.config import toml_text

    (tmp_path / "gains.toml").write_text(toml_text(gains, "tuned"))
    result = run_here("track", "hover:duration=2", "--gains", tmp_path / "gains.toml",
                      "--no-figures", "--quiet", "-o", tmp_path / "hover")
    assert result.returncode == 0, result.stderr
    parameters = json.loads((tmp_path / "hover" / "parameters.json").read_text())
    assert np.allclose(parameters["gains"]["velocity"]["kp"], [6.0, 6.0, 6.0])
