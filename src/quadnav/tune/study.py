"""The Optuna study behind ``quadnav tune``: :func:`run_study`.

Trials are asked ``parallel`` at a time, evaluated together (on local worker processes or
on Ray, by the caller's ``evaluate``) and told in the order they were asked, so a study
depends on its seed and on ``parallel`` only — not on how many workers evaluate it, nor
on which finishes first — and the same seed repeats it, locally and on a cluster. The
first trial of a new study is the vehicle's own gains (:func:`~.space.starting_point`),
so the best trial is never worse than where the search began.

The study lives in an Optuna RDB storage (a SQLite file by default), so an interrupted
study resumes where it stopped: trials left running by the interruption (with all, some or
none of their parameters written) are marked failed and asked again, and the search space
is compared on the finished trials alone. (The sampler's random state is not stored, so a
resumed study goes on differently from one never interrupted.)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import optuna
from optuna.distributions import FloatDistribution
from optuna.trial import TrialState

from quadnav.errors import QuadnavError
from quadnav.tune.space import Knob

#: Samplers by their ``--sampler`` name.
SAMPLERS = ("tpe", "cmaes")


@dataclass(frozen=True)
class StudySettings:
    """How a study searches.

    Attributes:
        trials: trials the study should hold once done (those of an earlier, interrupted
            run count).
        sampler: ``tpe`` (Optuna's tree-structured Parzen estimator) or ``cmaes``.
        seed: seed of the sampler.
        storage: Optuna RDB URL, e.g. ``sqlite:///DIR/study.db``.
        name: the study's name in the storage.
        parallel: trials asked, evaluated and told together.
    """

    trials: int
    sampler: str
    seed: int
    storage: str
    name: str
    parallel: int


def _sampler(settings: StudySettings) -> optuna.samplers.BaseSampler:
    if settings.sampler == "cmaes":
        return optuna.samplers.CmaEsSampler(seed=settings.seed, warn_independent_sampling=False)
    return optuna.samplers.TPESampler(seed=settings.seed)


def open_study(settings: StudySettings, knobs: tuple[Knob, ...],
               start: dict[str, float]) -> optuna.Study:
    """The study named ``settings.name`` in ``settings.storage``, created (with ``start``
    enqueued as its first trial) or loaded; trials an interruption left running are
    marked failed. QuadnavError (one line) when the storage cannot be opened, or holds a
    study of that name whose finished trials searched other knobs (checked before anything
    is changed)."""
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    try:
        study = optuna.create_study(storage=settings.storage, study_name=settings.name,
                                    sampler=_sampler(settings), direction="minimize",
                                    load_if_exists=True)
    except Exception as error:  # SQLAlchemy's and Optuna's errors alike
        raise QuadnavError(f"cannot open the study storage {settings.storage}: "
                           f"{str(error).splitlines()[0]}") from None
    trials = study.get_trials(deepcopy=False)
    names = {knob.name for knob in knobs}
    if any(set(trial.params) != names for trial in trials
           if trial.state == TrialState.COMPLETE):
        raise QuadnavError(f"study {settings.name!r} in {settings.storage} searches other "
                           "gains (another --space); give another --study or --storage")
    for trial in trials:  # asked but never told: a stop came first, perhaps mid-way
        if trial.state == TrialState.RUNNING:  # through writing its parameters
            study.tell(trial.number, state=TrialState.FAIL)
    if not trials:
        study.enqueue_trial(start)
    return study


def completed(study: optuna.Study) -> int:
    """Trials of ``study`` that have a value."""
    return len(study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)))


def distributions(knobs: tuple[Knob, ...]) -> dict[str, FloatDistribution]:
    """Optuna's distribution of each knob."""
    return {knob.name: FloatDistribution(knob.low, knob.high, log=knob.log) for knob in knobs}


def run_study(study: optuna.Study, settings: StudySettings, knobs: tuple[Knob, ...],
              evaluate: Callable[[list[dict[str, float]]], list[float]],
              progress: Callable[[optuna.Study], None] | None = None) -> optuna.Study:
    """Ask, evaluate and tell trials until ``study`` holds ``settings.trials`` completed
    ones. ``evaluate`` takes the points of up to ``settings.parallel`` trials (knob name
    -> value) and returns their objectives, in order; ``progress`` is called after each
    round."""
    space = distributions(knobs)
    while (missing := settings.trials - completed(study)) > 0:
        asked = [study.ask(space) for _ in range(min(settings.parallel, missing))]
        values = evaluate([trial.params for trial in asked])
        for trial, value in zip(asked, values, strict=True):
            study.tell(trial, value)
        if progress is not None:
            progress(study)
    return study
