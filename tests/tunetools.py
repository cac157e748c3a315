"""A quick tuning set for the ``quadnav tune`` tests, and the trials of a study its run
kept."""

from __future__ import annotations

from pathlib import Path

from quadnav.cli.tune_command import DEFAULT_STUDY

#: Only references: a study over them flies in a fraction of a second per trial.
QUICK = """references = ["hover:duration=2", "step:axis=z,size=0.5,duration=3"]
gusts = [0.01]
"""


def study_trials(folder: Path) -> list[tuple[float, dict]]:
    """The objective and point of every trial of a run's study (its default name and
    storage: ``folder``/study.db), in their order, exactly as stored."""
    import optuna  # the optional quadnav[tune]

    study = optuna.load_study(study_name=DEFAULT_STUDY, storage=f"sqlite:///{folder / 'study.db'}")
    return [(trial.value, trial.params) for trial in study.trials]
