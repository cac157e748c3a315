"""A stop at any point of a tuning study leaves a study that resumes: a trial left running with
all, some or none of its gains written (a SIGTERM while Optuna writes them one by one) is
failed and asked again, and the search space is compared on the finished trials alone. On a
real SQLite Optuna study, the states the audit found (1 or 9 of 18 gains) and their kin."""

from __future__ import annotations

import optuna
import pytest
from optuna.trial import TrialState

from quadnav.errors import QuadnavError
from quadnav.tune.space import CASCADE, OUTER
from quadnav.tune.study import StudySettings, completed, distributions, open_study, run_study

#: A point inside every knob's range: where a new study starts.
START = {knob.name: (knob.low + knob.high) / 2 for knob in CASCADE}


def settings(tmp_path, trials: int) -> StudySettings:
    return StudySettings(trials=trials, sampler="tpe", seed=4, parallel=2,
                         storage=f"sqlite:///{tmp_path / 'study.db'}", name="quadnav-tune")


def objective(points: list[dict[str, float]]) -> list[float]:
    """A smooth function of the gains (the study's machinery is what is tested here)."""
    return [sum((value - START[name]) ** 2 for name, value in point.items())
            for point in points]


def stopped_while_asking(study: optuna.Study, written: int, trials: int = 1) -> None:
    """Leave ``trials`` trials running with only their first ``written`` gains stored, as a
    stop during ``study.ask`` (which writes them one by one) leaves them."""
    space = list(distributions(CASCADE).items())
    for _ in range(trials):
        trial = study.ask()
        for name, distribution in space[:written]:
            trial._suggest(name, distribution)


@pytest.mark.parametrize(("written", "running"), [(0, 1), (1, 1), (9, 2), (17, 1), (18, 2)])
def test_a_study_stopped_while_asking_resumes(tmp_path, written, running):
    first = open_study(settings(tmp_path, 2), CASCADE, START)
    run_study(first, settings(tmp_path, 2), CASCADE, objective)
    stopped_while_asking(first, written, running)

    again = open_study(settings(tmp_path, 4), CASCADE, START)
    states = [trial.state for trial in again.get_trials(deepcopy=False)]
    assert states == [TrialState.COMPLETE] * 2 + [TrialState.FAIL] * running
    run_study(again, settings(tmp_path, 4), CASCADE, objective)
    assert completed(again) == 4
    assert all(set(trial.params) == {knob.name for knob in CASCADE}
               for trial in again.get_trials(states=(TrialState.COMPLETE,)))


def test_a_stop_before_the_first_trial_was_told_resumes_from_the_start(tmp_path):
    study = open_study(settings(tmp_path, 2), CASCADE, START)
    stopped_while_asking(study, 0)  # the enqueued start, asked, not yet written
    again = open_study(settings(tmp_path, 2), CASCADE, START)
    run_study(again, settings(tmp_path, 2), CASCADE, objective)
    assert completed(again) == 2


def test_another_space_is_refused_before_anything_is_changed(tmp_path):
    study = open_study(settings(tmp_path, 2), CASCADE, START)
    run_study(study, settings(tmp_path, 2), CASCADE, objective)
    stopped_while_asking(study, 5)
    with pytest.raises(QuadnavError, match="searches other gains"):
        open_study(settings(tmp_path, 4), OUTER, {k.name: START[k.name] for k in OUTER})
    states = [trial.state for trial in study.get_trials(deepcopy=False)]
    assert states[-1] == TrialState.RUNNING  # left for the run of the right space
