"""One mission of a batch: :func:`fly_row` flies a :class:`~.grid.MissionSpec` and returns
its row of the results table.

Each mission is a :class:`~quadnav.missionconfig.MissionConfig` (:func:`mission_config`),
built as every command builds one. Everything a mission reads from files (maps, gains,
the vehicle) is loaded once by the parent into a :class:`BatchContext`
(:func:`load_context`) and sent to the workers, so a worker on another machine needs no
file of the driver's but the plug-ins' (controllers, planners, references, winds named
``path/to/file.py:Name``), which each worker loads from the spec's text, by the file's
absolute path. A mission depends only on its spec and the context: the planner's
budget binds by samples, and the gusts, the vehicle spread and a start and goal drawn for
a map without its own all come from the seeds.

A worker makes each query, plan and reference once (:mod:`~quadnav.batch.stages`): the
missions it flies that share them share them, and give the rows they give flown alone.
"""

from __future__ import annotations

import hashlib
import warnings
from dataclasses import dataclass, field, replace
from functools import cached_property
from itertools import product
from pathlib import Path
from typing import Any

import numpy as np

from quadnav.batch.grid import DEFAULT_GAINS, BatchSpec, FixedSettings, MissionSpec
from quadnav.batch.stages import StageCache, plan_key, query_key, worker_cache, world_hash
from quadnav.batch.table import mission_row
from quadnav.config import as_plain
from quadnav.control.registry import controller_gains
from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.mission import Mission, MissionSettings, fly_problem
from quadnav.missionconfig import MissionConfig, MissionFiles, spread_factors, vehicle_from
from quadnav.planning import PlannerSettings, PlanningProblem, make_problem
from quadnav.trajectory.generate import TrajectorySettings
from quadnav.vehicle.params import VehicleParams
from quadnav.world import World, load_world
from quadnav.world.builtin import DEFAULT_MARGIN

#: Free points of the inflated map drawn for a mission whose map has no start or goal;
#: the start and goal are the two most distant of them that :func:`make_problem` accepts.
DRAWN_POINTS = 32
#: Pairs of drawn points tried, most distant first, before the mission is refused.
DRAWN_TRIES = 8
#: The seed's stream of the drawn start and goal (the spread's is
#: :data:`~quadnav.missionconfig.SPREAD_STREAM`).
QUERY_STREAM = 2


@dataclass(frozen=True, eq=False)
class BatchContext:
    """What every mission of a batch needs besides its own spec, loaded from files once.

    Attributes:
        fixed: the settings every mission shares.
        vehicle: the nominal vehicle (``fixed.vehicle`` loaded).
        worlds: each map of the grid by its name (:attr:`MapEntry.map`).
        gains: the gains of each controller and gains entry of the grid, loaded, by
            (controller, entry).
        plugins: a hash of each plug-in file the grid names, by its absolute path.
        plans: the folder where the workers keep the plans they make
            (:class:`~quadnav.batch.stages.StageCache`); None: each keeps them in memory
            alone.
    """

    fixed: FixedSettings
    vehicle: VehicleParams
    worlds: dict[str, World]
    gains: dict[tuple[str, str], Any]
    plugins: dict[str, str] = field(default_factory=dict)
    plans: Path | None = None

    @cached_property
    def world_hashes(self) -> dict[str, str]:
        """A hash of each map's content (:func:`~quadnav.batch.stages.world_hash`), by
        its name."""
        return {name: world_hash(world) for name, world in self.worlds.items()}

    def fingerprint(self) -> dict:
        """What the files gave, JSON-ready: the vehicle, the gains of each controller, a
        hash of each map and (when the grid names any) of each plug-in file, so a batch
        folder can tell when a file changed under it."""
        gains: dict[str, dict[str, Any]] = {}
        for (controller, name), values in self.gains.items():
            gains.setdefault(controller, {})[name] = as_plain(values)
        plugins = {"plugins": dict(self.plugins)} if self.plugins else {}
        return {"vehicle": as_plain(self.vehicle), "gains": gains,
                "maps": dict(self.world_hashes)} | plugins

    def files(self, mission: MissionSpec) -> MissionFiles:
        """The vehicle and gains ``mission`` flies with, as loaded."""
        return MissionFiles(self.vehicle, self.gains[mission.controller, mission.gains])


def plugin_files(spec: BatchSpec) -> dict[str, str]:
    """A hash of each plug-in file the grid of ``spec`` names (``path/to/file.py:Name``,
    the path resolved), by its path."""
    texts = (*spec.controllers, *spec.planners, *spec.references,
             *(wind for wind in spec.winds if isinstance(wind, str)))
    paths = sorted({where for where, colon, _ in (text.partition(":") for text in texts)
                    if colon and where.endswith(".py")})
    return {path: hashlib.sha256(Path(path).read_bytes()).hexdigest()[:16] for path in paths}


def _gains(spec: BatchSpec, vehicle: VehicleParams) -> dict[tuple[str, str], Any]:
    """The gains of every controller and gains entry of ``spec`` flying ``vehicle``;
    QuadnavError naming both for a pair that does not fit (a gains file of the cascade
    for a controller without gains, say)."""
    gains = {}
    for controller, name in product(spec.controllers, spec.gains):
        try:
            gains[controller, name] = controller_gains(
                controller, vehicle, None if name == DEFAULT_GAINS else name)
        except QuadnavError as error:
            if len(spec.controllers) == 1:
                raise
            raise QuadnavError(f"controllers {controller} with gains {name}: {error}"
                               ) from None
    return gains


def load_context(spec: BatchSpec) -> BatchContext:
    """Load the vehicle, maps, gains and plug-in files of ``spec``; QuadnavError for a bad
    file or a setting out of range, before any mission flies."""
    vehicle = vehicle_from(spec.fixed.vehicle)
    worlds = {entry.map: load_world(entry.map) for entry in spec.maps}
    context = BatchContext(spec.fixed, vehicle, worlds, _gains(spec, vehicle),
                           plugin_files(spec))
    # the settings of each controller, gains, trajectory and wind, on the first mission
    first = spec.missions()[0]
    for controller, gains, (method, reference), wind in product(
            spec.controllers, spec.gains, spec.trajectories, spec.winds):
        mission_settings(context, replace(first, controller=controller, gains=gains,
                                          method=method, reference=reference, wind=wind))
    return context


def mission_config(fixed: FixedSettings, mission: MissionSpec) -> MissionConfig:
    """The mission ``mission`` of a batch whose fixed settings are ``fixed``: its map
    entry's query (its margin, else the batch's), its seeds, speed, disturbances, planner,
    controller and gains, trajectory method or class, and the batch's vehicle, trajectory
    timing, budget and rates."""
    entry = mission.map
    query = {"start": entry.start, "goal": entry.goal,
             "margin": fixed.margin if entry.margin is None else entry.margin}
    gains = {} if mission.gains == DEFAULT_GAINS else {"gains": mission.gains}
    trajectory = ({"reference": mission.reference} if mission.reference is not None
                  else {"method": mission.method})
    wind = ({"wind_model": mission.wind} if isinstance(mission.wind, str)
            else {"wind": mission.wind})
    return MissionConfig.from_table({
        "map": entry.map, "seed": mission.seed, "vehicle": fixed.vehicle,
        "query": {key: value for key, value in query.items() if value is not None},
        "planner": {"name": mission.planner, "time": fixed.time_cap,
                    "improve": fixed.improve, "stall": fixed.stall,
                    "stall_fraction": fixed.stall_fraction},
        "trajectory": trajectory | {"timing": fixed.timing, "speed": mission.speed,
                                    "accel": fixed.accel},
        "controller": {"name": mission.controller} | gains,
        "simulation": {"physics_rate": fixed.physics_rate,
                       "control_rate": fixed.control_rate, "settle": fixed.settle,
                       "seed": mission.sim_seed},
        "disturbances": wind | {"gusts": mission.gusts, "spread": mission.spread},
    }, source="the batch spec")


def mission_settings(context: BatchContext, mission: MissionSpec) -> MissionSettings:
    """The settings ``mission`` flies with (:meth:`MissionConfig.settings` of its
    :func:`mission_config`, with the context's vehicle and gains); the plant is the
    nominal vehicle scaled by :func:`~quadnav.missionconfig.spread_factors` (of the
    simulation's seed).

    Raises:
        QuadnavError: settings that do not fit together (e.g. a physics rate that is not a
            multiple of the control rate, a spread vehicle that cannot lift itself).
    """
    return mission_config(context.fixed, mission).settings(context.files(mission))


def mission_margin(context: BatchContext, mission: MissionSpec) -> float:
    """The mission's margin, m: its map entry's, else the batch's, else the map's own,
    else 0.2."""
    config = mission_config(context.fixed, mission)
    return config.margin(context.worlds[mission.map.map])


def given_query(context: BatchContext, mission: MissionSpec
                ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The start and goal given for the mission (its map entry's, else the map's own),
    each (3,) m or None when there is none, to be drawn from the seed."""
    return mission_config(context.fixed, mission).ends(context.worlds[mission.map.map])


def mission_problem(context: BatchContext, mission: MissionSpec, body: np.ndarray,
                    cache: StageCache | None = None) -> PlanningProblem:
    """The mission's checked query for a vehicle whose body has half extents ``body``
    (3,) m (from ``cache`` when it has it). A start or goal that is not given is drawn
    from the seed: of :data:`DRAWN_POINTS` free points of the inflated map, the most
    distant pair (or the point most distant from the given end) that :func:`make_problem`
    accepts.

    Raises:
        QuadnavError: a bad query (a given point in a block, disconnected ends).
    """
    config = mission_config(context.fixed, mission)
    world = context.worlds[mission.map.map]
    margin = config.margin(world)
    start, goal = config.ends(world)
    if cache is None:
        return _query(world, start, goal, margin, body, mission.seed)
    drawn = None if start is not None and goal is not None else mission.seed
    key = query_key(context.world_hashes[mission.map.map], start, goal, margin, body, drawn)
    return cache.problem(key, lambda: _query(world, start, goal, margin, body, mission.seed))


def _query(world: World, start: np.ndarray | None, goal: np.ndarray | None, margin: float,
           body: np.ndarray, seed: int) -> PlanningProblem:
    """The checked query of :func:`mission_problem`, each end not given drawn from
    ``seed``."""
    if start is not None and goal is not None:
        return make_problem(world, start, goal, margin, body)
    rng = np.random.default_rng([seed, QUERY_STREAM])
    points = world.inflate(margin).sample_free(DRAWN_POINTS, rng)
    starts = points if start is None else start[None]
    goals = points if goal is None else goal[None]
    distances = np.linalg.norm(starts[:, None] - goals[None], axis=2)
    order = np.argsort(-distances, axis=None, kind="stable")
    error = None
    for flat in order[:DRAWN_TRIES]:
        i, j = np.unravel_index(flat, distances.shape)
        try:
            return make_problem(world, starts[i], goals[j], margin, body)
        except QuadnavError as refused:
            error = refused
    raise QuadnavError(f"no start and goal drawn from seed {seed} could be joined: {error}")


def fly_mission_spec(context: BatchContext, mission: MissionSpec,
                     cache: StageCache | None = None) -> Mission:
    """Fly ``mission`` (planning warnings silenced: a batch reports in its table), its
    query, plan and reference from ``cache`` when it has them (kept there when made); the
    same mission either way.

    Raises:
        QuadnavError: a bad query or settings (see :func:`mission_problem`).
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)
        settings = mission_settings(context, mission)
        problem = mission_problem(context, mission, settings.body, cache)
        if cache is None:
            return fly_problem(problem, settings)
        return cache.fly(context.world_hashes[mission.map.map], problem, settings)[1]


def fly_row(context: BatchContext, mission: MissionSpec) -> dict:
    """The results row of ``mission`` (:func:`flown_row`), flown with this worker's
    cache (:func:`~quadnav.batch.stages.worker_cache` of ``context.plans``)."""
    return flown_row(context, mission, worker_cache(context.plans))


def fly_rows(context: BatchContext, missions: list[MissionSpec]) -> list[dict]:
    """The rows of ``missions`` (:func:`fly_row`), flown one after the other on one
    worker: missions that share a plan, sent together, find it in its cache."""
    return [fly_row(context, mission) for mission in missions]


def flown_row(context: BatchContext, mission: MissionSpec, cache: StageCache | None = None
              ) -> dict:
    """The results row of ``mission`` (:func:`~.table.mission_row`), with the key of the
    plan it flew (:func:`~quadnav.batch.stages.plan_key`), its stages from ``cache`` when
    given. Never raises for the mission's own failure: a refused query or setting is a row
    with ``success`` false and the reason in ``error``."""
    start, goal = given_query(context, mission)
    drawn = start is None or goal is None
    try:
        flown = fly_mission_spec(context, mission, cache)
    except QuadnavError as error:
        return refused_row(context, mission, str(error))
    key = plan_key(context.world_hashes[mission.map.map], flown.problem, flown.settings)
    return mission_row(mission, _factors(mission), drawn, flown, plan_key=key)


def refused_row(context: BatchContext, mission: MissionSpec, reason: str) -> dict:
    """The row of ``mission`` refused (or given up) for ``reason``: ``success`` false, the
    reason in ``error`` and what is known of its query."""
    start, goal = given_query(context, mission)
    return mission_row(mission, _factors(mission), start is None or goal is None, None,
                       reason, start, goal, mission_margin(context, mission))


def refused_rows(context: BatchContext, missions: list[MissionSpec], reason: str
                 ) -> list[dict]:
    """The rows of a job of ``missions`` (:func:`fly_rows`) given up for ``reason``."""
    return [refused_row(context, mission, reason) for mission in missions]


def _factors(mission: MissionSpec) -> tuple[float, float, float]:
    return spread_factors(mission.spread, mission.flight_seed)


def warm_up(context: BatchContext) -> None:
    """Load every compiled kernel a mission runs (from numba's cache) by flying a short
    mission through a small built-in world."""
    world = load_world("window:size=4x6x3,walls=1")
    settings = MissionSettings(planning=PlannerSettings(improve_iterations=100),
                               trajectory=TrajectorySettings(v_max=1.0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)
        fly_problem(make_problem(world, None, None, DEFAULT_MARGIN, settings.body), settings)
