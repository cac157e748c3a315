"""Each plan and trajectory made once per distinct input: :class:`StageCache`.

Missions that differ only in what happens after the trajectory is made (the wind, the
gusts, the vehicle spread, the controller and its gains, the simulation's seed) fly one
plan and one trajectory. Each stage has a key made from its real inputs:

* the query (:func:`query_key`): the map's content (:func:`world_hash`), the start and goal
  given (or the seed they are drawn from), the margin and the body kept inside the map;
* the plan (:func:`plan_key`): the map's content, the checked query as planned (the margin,
  the legs, the goal asked), the planner and every planning setting (its seed included),
  and how the path is refined;
* the trajectory (:func:`reference_key`): the plan's key, and for quadnav's trajectory the
  trajectory settings, ``fastest``, and the vehicle it is made for with the gains whose
  limits bound it (:attr:`~quadnav.mission.MissionSettings.limit_gains`); for a trajectory
  class of your own its spec, its duration, the control rate it is sampled at and the goal
  tolerance its ends are checked with.

A worker process keeps the last :data:`MEMORY_SIZE` of each in memory
(:func:`worker_cache`) and, with a folder (a batch's ``plans/``), each solved plan on disk
as ``KEY.npz``, written atomically, so that a resumed batch plans none again. A plan read
from disk is checked before it is flown, as any input from a run folder: a file that is
not a plan of this format and key, or whose path does not run from the query's start to
its goal along its legs, keeping the margin off them, measured exactly
(:func:`~quadnav.planning.plain.path_fault`), is ignored and the plan made again. A cached
plan keeps no search tree (the batch draws none), and its ``planning_time_s`` is the wall
time of the search that made it.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import time
import zipfile
from collections import Counter, OrderedDict
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from quadnav import __version__
from quadnav.config import as_plain
from quadnav.errors import QuadnavError, WriteError
from quadnav.files import atomic_output
from quadnav.mission import (
    Mission,
    MissionSettings,
    fly_reference,
    make_reference,
    plan_mission,
)
from quadnav.planning import PlanningProblem, PlanResult, PlanStats, PostStep
from quadnav.planning.plain import path_fault
from quadnav.trajectory.model import Trajectory
from quadnav.trajectory.references.plain import FlatOutputReference
from quadnav.world.model import World

#: Entries of each stage a worker keeps in memory, the least recently used dropped first.
MEMORY_SIZE = 64
#: The version of the plan files' format.
PLAN_FORMAT = 1
#: The hex digits of a key.
KEY_DIGITS = 32

Reference = Trajectory | FlatOutputReference
Value = TypeVar("Value")


def world_hash(world: World) -> str:
    """A short hash of what ``world`` holds (its boundary, blocks, own start and goal and
    margin; not its name or colours)."""
    parts = [world.boundary, world.blocks, world.start, world.goal, world.margin]
    digest = hashlib.sha256(repr([None if p is None else np.asarray(p).tolist()
                                  for p in parts]).encode())
    return digest.hexdigest()[:16]


def _key(parts: list[Any]) -> str:
    """The hash of ``parts`` (JSON-ready; floats exactly) and quadnav's version."""
    text = json.dumps([__version__, *parts], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:KEY_DIGITS]


def _listed(point: Any) -> list[float] | None:
    return None if point is None else np.asarray(point, dtype=np.float64).tolist()


def query_key(world: str, start: Any, goal: Any, margin: float, body: Any,
              seed: int | None) -> str:
    """The key of a checked query on the map whose :func:`world_hash` is ``world``: the
    ``start`` and ``goal`` given ((3,) m, None: the map's own or drawn), the ``margin``
    m, the ``body``'s half extents (3,) m, and the ``seed`` a start or goal is drawn from
    (None: neither is drawn)."""
    return _key(["query", world, _listed(start), _listed(goal), float(margin),
                 _listed(body), seed])


def plan_key(world: str, problem: PlanningProblem, settings: MissionSettings) -> str:
    """The key of the plan of ``problem`` (its map's :func:`world_hash` ``world``) with
    ``settings``: the planner, every planning setting, and the refinement."""
    return _key(["plan", world, problem.margin, problem.start_leg.tolist(),
                 problem.goal_leg.tolist(), _listed(problem.asked_goal), settings.planner,
                 as_plain(settings.planning), settings.refine,
                 settings.reference is None])  # a class of your own: shortcut alone


def reference_key(plan: str, settings: MissionSettings) -> str:
    """The key of the reference flown along the plan whose key is ``plan``, made with
    ``settings`` (see the module docstring)."""
    if settings.reference is not None:
        made = [settings.reference, settings.reference_duration, settings.sim.control_rate,
                settings.sim.goal_tolerance]
    else:
        made = [as_plain(settings.trajectory), settings.fastest, as_plain(settings.vehicle),
                as_plain(settings.limit_gains)]
    return _key(["reference", plan, made])


class _Recent(OrderedDict[str, Any]):
    """At most ``size`` entries, the least recently used dropped first."""

    def __init__(self, size: int) -> None:
        super().__init__()
        self.size = size

    def get_recent(self, key: str) -> Any:
        if key not in self:
            return None
        self.move_to_end(key)
        return self[key]

    def put(self, key: str, value: Any) -> None:
        self[key] = value
        self.move_to_end(key)
        while len(self) > self.size:
            self.popitem(last=False)


class StageCache:
    """The queries, plans and references of one worker, by key (see the module docstring).

    Attributes:
        folder: where solved plans are kept as ``KEY.npz`` (None: in memory alone).
        made: how many of each stage this cache made (``query``, ``plan``, ``reference``)
            rather than found.
        read: how many plans it read from ``folder`` (and found sound).
    """

    def __init__(self, folder: Path | None = None, size: int = MEMORY_SIZE) -> None:
        self.folder = folder
        self.made: Counter[str] = Counter()
        self.read = 0
        self._kept = {stage: _Recent(size) for stage in ("query", "plan", "reference")}

    def _found(self, stage: str, key: str, make: Callable[[], Value]) -> Value:
        """The ``stage`` entry of ``key``, made by ``make`` when not kept."""
        kept = self._kept[stage].get_recent(key)
        if kept is None:
            kept = make()
            self.made[stage] += 1
            self._kept[stage].put(key, kept)
        return kept

    def problem(self, key: str, make: Callable[[], PlanningProblem]) -> PlanningProblem:
        """The checked query of ``key`` (:func:`query_key`), made by ``make`` (which may
        raise QuadnavError, then made again next time) when not kept."""
        return self._found("query", key, make)

    def plan(self, world: str, problem: PlanningProblem, settings: MissionSettings
             ) -> tuple[str, Mission]:
        """The key of ``problem``'s plan with ``settings`` and the plan (a mission with
        neither trajectory nor flight: :func:`~quadnav.mission.plan_mission`), from memory,
        else from the folder, else made."""
        key = plan_key(world, problem, settings)
        kept = self._kept["plan"].get_recent(key)
        if kept is None:
            kept = self._read(key, problem, settings)
            if kept is None:
                kept = _treeless(plan_mission(problem, settings))
                self.made["plan"] += 1
                self._write(key, kept)
            self._kept["plan"].put(key, kept)
        return key, dataclasses.replace(kept, settings=settings)

    def reference(self, plan: str, planned: Mission, settings: MissionSettings
                  ) -> tuple[Reference, MissionSettings, float]:
        """The reference along ``planned``'s path (a solved plan whose key is ``plan``)
        made with ``settings`` (:func:`~quadnav.mission.make_reference`), ``settings``
        with the trajectory settings that made it, and the wall time it took to make, s."""
        def make() -> tuple[Reference, Any, float]:
            began = time.perf_counter()
            reference, chosen = make_reference(planned.problem, planned.plan.path, settings)
            return reference, chosen.trajectory, time.perf_counter() - began

        reference, trajectory, seconds = self._found(
            "reference", reference_key(plan, settings), make)
        return reference, dataclasses.replace(settings, trajectory=trajectory), seconds

    def fly(self, world: str, problem: PlanningProblem, settings: MissionSettings
            ) -> tuple[str, Mission]:
        """The key of the plan flown and the mission ``problem`` (on the map whose
        :func:`world_hash` is ``world``) flown with ``settings``, as
        :func:`~quadnav.mission.fly_problem` flies it, its plan and reference found here."""
        key, planned = self.plan(world, problem, settings)
        if not planned.plan.solved:
            return key, planned
        reference, settings, seconds = self.reference(key, planned, settings)
        return key, fly_reference(planned, reference, settings, seconds)

    # ------------------------------------------------------------------------- on disk
    def _path(self, key: str) -> Path | None:
        return None if self.folder is None else self.folder / f"{key}.npz"

    def _write(self, key: str, planned: Mission) -> None:
        """Keep a solved plan in the folder as ``KEY.npz``, atomically; where it cannot be
        written (no room, the folder's place taken by a file), in memory alone: a mission
        never fails for its cache."""
        path = self._path(key)
        if path is None or not planned.plan.solved:  # no path found: searched again
            return
        result = planned.plan
        stats = result.stats
        info = {"format": PLAN_FORMAT, "key": key, "planner": result.planner,
                "seed": result.seed, "message": result.message,
                "raw_length": planned.raw_length, "planning_s": planned.timings["planning"],
                "stats": {"iterations": stats.iterations, "nodes": stats.nodes,
                          "seconds": stats.seconds, "time_to_first": stats.time_to_first,
                          "stopped_by": stats.stopped_by,
                          "setup_seconds": stats.setup_seconds,
                          "post": [dataclasses.astuple(step) for step in stats.post]}}
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            with atomic_output(path) as tmp, tmp.open("wb") as file:
                np.savez(file, path=result.path, cost_history=stats.cost_history,
                         info=np.array(json.dumps(info)))
        except (OSError, WriteError):  # no room, no folder: the plan is kept in memory
            return

    def _read(self, key: str, problem: PlanningProblem, settings: MissionSettings
              ) -> Mission | None:
        """The plan of ``key`` kept in the folder, or None: none there, or a file that is
        not a sound plan of ``problem`` with this key (see the module docstring)."""
        path = self._path(key)
        if path is None or not path.is_file():
            return None
        try:
            with np.load(path, allow_pickle=False) as data:
                points = np.array(data["path"], dtype=np.float64)
                history = np.array(data["cost_history"], dtype=np.float64)
                info = json.loads(str(data["info"][()]))
            planned = _planned(info, key, points, history, problem, settings)
        except (OSError, ValueError, KeyError, TypeError, IndexError, AttributeError,
                zipfile.BadZipFile, QuadnavError):
            return None
        if planned is not None:
            self.read += 1
        return planned


def _planned(info: dict, key: str, points: np.ndarray, history: np.ndarray,
             problem: PlanningProblem, settings: MissionSettings) -> Mission | None:
    """The plan a file held (its ``info``, path ``points`` (N, 3) m and ``history``), or
    None when it is not a sound plan of ``problem`` with ``key``. Raises ValueError,
    KeyError or TypeError for values of the wrong kind."""
    stats = info["stats"]
    if (info["format"] != PLAN_FORMAT or info["key"] != key
            or points.ndim != 2 or points.shape[1] != 3 or len(points) < 2
            or not np.isfinite(points).all()
            or path_fault(problem.world, problem.margin, problem.search_part(points),
                          problem.free_world) is not None):
        return None
    post = tuple(PostStep(str(name), float(length), int(vertices), float(seconds))
                 for name, length, vertices, seconds in stats["post"])
    first = stats["time_to_first"]
    result = PlanResult(
        str(info["planner"]), True, points, np.zeros((0, 3)), np.zeros(0, dtype=np.int64),
        PlanStats(int(stats["iterations"]), int(stats["nodes"]), float(stats["seconds"]),
                  None if first is None else float(first), history, post,
                  None if stats["stopped_by"] is None else str(stats["stopped_by"]),
                  float(stats["setup_seconds"])),
        int(info["seed"]), str(info["message"]))
    return Mission(problem, result, float(info["raw_length"]), None, None,
                   {"planning": float(info["planning_s"])}, settings)


def _treeless(planned: Mission) -> Mission:
    """``planned`` without its search tree (which only figures draw)."""
    plan = planned.plan.replace(tree_nodes=np.zeros((0, 3)),
                                tree_parents=np.zeros(0, dtype=np.int64))
    return dataclasses.replace(planned, plan=plan)


#: This process's caches, by folder (see :func:`worker_cache`).
_WORKER_CACHES: dict[Path | None, StageCache] = {}


def worker_cache(folder: Path | None) -> StageCache:
    """This process's cache keeping its plans in ``folder`` (None: in memory alone), made
    on first use: every mission a worker flies shares it."""
    if folder not in _WORKER_CACHES:
        _WORKER_CACHES[folder] = StageCache(folder)
    return _WORKER_CACHES[folder]
