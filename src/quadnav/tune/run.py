"""A gain-tuning run, start to end: :class:`TuneRun`.

Everything is read and checked first (the vehicle, the starting gains, the sets, the gain
tables compared), then the sets' missions are planned once, then the study runs its trials
on the executor's workers (:mod:`quadnav.batch.executor`: local processes or Ray), each
trial flying every training item with its gains. At the end every gain set compared — the
vehicle's own, the course tables, the tuned gains — flies both sets, and the folder gets
``gains.toml`` (the tuned gains), ``tune.json``, ``trials.csv`` and ``report.html``.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import optuna

from quadnav.batch.executor import Executor, open_executor
from quadnav.batch.fly_one import warm_up
from quadnav.batch.stages import StageCache
from quadnav.config import as_plain
from quadnav.control.gains import Gains
from quadnav.control.registry import DEFAULT_CONTROLLER, controller_gains
from quadnav.errors import PlanningWarning
from quadnav.missionconfig import vehicle_from
from quadnav.tune.evaluate import Flights, fly_item, objective, scores
from quadnav.tune.sets import TuneItem, TuneSet, read_set, set_items
from quadnav.tune.space import Knob, space_knobs, starting_point, with_values
from quadnav.tune.study import StudySettings, open_study, run_study
from quadnav.vehicle.params import VehicleParams

#: The name of the starting gains among the gain sets compared.
OWN = "own"
#: The name of the tuned gains among the gain sets compared.
TUNED = "tuned"


@dataclass(frozen=True)
class TuneSettings:
    """What a tuning run searches, on what, and how.

    Attributes:
        vehicle: a vehicle preset or TOML file.
        gains: the starting gains over the vehicle's own (a course table's name or a
            TOML file), or None for the vehicle's own.
        space: the search space's name (:data:`~.space.SPACES`).
        study: the study's settings.
        training: the set tuned on: a shipped set's name or a TOML file.
        held_out: the set compared on.
        compare: gain tables compared besides the starting and the tuned gains.
    """

    vehicle: str
    gains: str | None
    space: str
    study: StudySettings
    training: str
    held_out: str
    compare: tuple[str, ...]


@dataclass(frozen=True, eq=False)
class Outcome:
    """A finished tuning run.

    Attributes:
        tuned: the best gains found.
        best_trial: the number of the trial that found them (0: the starting gains).
        best_params: its point of the space (knob name -> value).
        best_value: its objective on the training set.
        trials: the study's completed trials.
        scores: ``{set name: {gain set name: scores}}`` (:func:`~.evaluate.scores`) for the
            training and held-out sets.
        flights: ``{set name: {gain set name: [metrics per item]}}``.
        items: ``{set name: [item names]}``.
        wall_time: s, from the start of the run to the comparison's end.
    """

    tuned: Gains
    best_trial: int
    best_params: dict[str, float]
    best_value: float
    trials: list[optuna.trial.FrozenTrial]
    scores: dict[str, dict[str, dict]]
    flights: dict[str, dict[str, list[dict]]]
    items: dict[str, list[str]]
    wall_time: float


class TuneRun:
    """A tuning run with every input read and checked (QuadnavError for bad input, before
    anything is written); :meth:`run` does the rest."""

    def __init__(self, settings: TuneSettings) -> None:
        self.settings = settings
        self.vehicle: VehicleParams = vehicle_from(settings.vehicle)
        self.start: Gains = controller_gains(DEFAULT_CONTROLLER, self.vehicle, settings.gains)
        self.knobs: tuple[Knob, ...] = space_knobs(settings.space)
        self.sets: dict[str, TuneSet] = {
            "training": read_set(settings.training, settings.vehicle),
            "held-out": read_set(settings.held_out, settings.vehicle)}
        self.tables: dict[str, Gains] = {
            name: controller_gains(DEFAULT_CONTROLLER, self.vehicle, name)
            for name in settings.compare}
        self.began = time.perf_counter()

    def plan(self) -> dict[str, list[TuneItem]]:
        """Each set's items, its missions planned for the vehicle with the starting gains,
        a plan or trajectory two missions share made once (QuadnavError for a mission that
        cannot be planned)."""
        cache = StageCache()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PlanningWarning)
            return {name: set_items(tune_set, self.vehicle, self.start, cache)
                    for name, tune_set in self.sets.items()}

    def run(self, items: dict[str, list[TuneItem]], workers: int | None = None,
            ray: bool = False, address: str | None = None,
            on_round: Callable[[optuna.Study], None] | None = None) -> Outcome:
        """Run the study to its trial count, then compare the gain sets on both sets."""
        settings = self.settings
        everything = [*items["training"], *items["held-out"]]
        flights = Flights(self.vehicle, self.start, tuple(everything))
        ranges = {"training": range(len(items["training"])),
                  "held-out": range(len(items["training"]), len(everything))}
        study = open_study(settings.study, self.knobs, starting_point(self.start, self.knobs))
        with open_executor(flights, warm_up, workers, ray, address) as executor:
            def evaluate(points: list[dict[str, float]]) -> list[float]:
                flown = _fly(executor, points, ranges["training"])
                return [objective(metrics) for metrics in flown]

            run_study(study, settings.study, self.knobs, evaluate, on_round)
            best = study.best_trial
            tuned = with_values(self.start, best.params)
            gain_sets = {OWN: self.start, **self.tables, TUNED: tuned}
            compared = {set_name: dict(zip(gain_sets, _fly(executor, list(gain_sets.values()),
                                                          indices), strict=True))
                        for set_name, indices in ranges.items()}
        return Outcome(
            tuned=tuned, best_trial=best.number, best_params=best.params,
            best_value=best.value,
            trials=study.get_trials(deepcopy=False,
                                    states=(optuna.trial.TrialState.COMPLETE,)),
            scores={set_name: {name: scores(flown) for name, flown in by_gains.items()}
                    for set_name, by_gains in compared.items()},
            flights=compared,
            items={name: [item.name for item in set_items_] for name, set_items_ in items.items()},
            wall_time=time.perf_counter() - self.began)

    def record(self, outcome: Outcome) -> dict[str, Any]:
        """``tune.json``: the settings, the study, the best trial and the comparison."""
        settings = self.settings
        return {
            "vehicle": self.vehicle.name, "starting_gains": settings.gains or OWN,
            "space": settings.space, "knobs": [knob.name for knob in self.knobs],
            "study": as_plain(settings.study), "training": settings.training,
            "held_out": settings.held_out, "trials": len(outcome.trials),
            "best_trial": outcome.best_trial, "best_objective": outcome.best_value,
            "best_params": outcome.best_params,
            "scores": outcome.scores, "items": outcome.items, "flights": outcome.flights,
            "wall_time_s": outcome.wall_time,
        }


def _fly(executor: Executor, gain_points: Sequence[dict[str, float] | Gains],
         indices: range) -> list[list[dict]]:
    """Every item in ``indices`` flown with every point (or Gains) of ``gain_points``, on
    the executor; returns the metrics per point, in the items' order."""
    jobs = [(point, index) for point in gain_points for index in indices]
    flown: list[dict | None] = [None] * len(jobs)
    for position, metrics in executor.map_unordered(fly_item, jobs):
        flown[position] = metrics
    count = len(indices)
    return [flown[k * count:(k + 1) * count] for k in range(len(gain_points))]


def default_storage(folder: Path) -> str:
    """The study's storage unless ``--storage`` says otherwise: ``DIR/study.db``."""
    return f"sqlite:///{(folder / 'study.db').resolve()}"

