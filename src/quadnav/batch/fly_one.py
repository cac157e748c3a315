"""One mission of a batch: :func:`fly_row` flies a :class:`~.grid.MissionSpec` and returns
its row of the results table.

Everything a mission reads from files (maps, gains, the vehicle) is loaded once by the
parent into a :class:`BatchContext` (:func:`load_context`) and sent to the workers, so a
worker on another machine needs no file of the driver's. A mission depends only on its
spec and the context: the planner's budget binds by samples, and the gusts, the vehicle
spread and a start and goal drawn for a map without its own all come from the seed.
"""

from __future__ import annotations

import hashlib
import warnings
from dataclasses import dataclass

import numpy as np

from quadnav.batch.grid import DEFAULT_GAINS, BatchSpec, FixedSettings, MissionSpec
from quadnav.batch.table import mission_row
from quadnav.config import as_plain
from quadnav.control.gains import Gains, load_gains
from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.mission import Mission, MissionSettings, fly_problem
from quadnav.planning import PlannerSettings, PlanningProblem, make_problem
from quadnav.sim.settings import SimSettings, default_record_rate
from quadnav.trajectory.generate import TrajectorySettings
from quadnav.trajectory.timing import DEFAULT_V_MAX
from quadnav.vehicle.params import VehicleParams, load_params
from quadnav.world import World, load_world
from quadnav.world.builtin import DEFAULT_MARGIN

#: Free points of the inflated map drawn for a mission whose map has no start or goal;
#: the start and goal are the two most distant of them that :func:`make_problem` accepts.
DRAWN_POINTS = 32
#: Pairs of drawn points tried, most distant first, before the mission is refused.
DRAWN_TRIES = 8
#: Streams of the seed's random numbers, so each draw is independent of the others.
SPREAD_STREAM, QUERY_STREAM = 1, 2


@dataclass(frozen=True, eq=False)
class BatchContext:
    """What every mission of a batch needs besides its own spec, loaded from files once.

    Attributes:
        fixed: the settings every mission shares.
        vehicle: the nominal vehicle (``fixed.vehicle`` loaded).
        worlds: each map of the grid by its name (:attr:`MapEntry.map`).
        gains: each gains entry of the grid loaded, by its name.
    """

    fixed: FixedSettings
    vehicle: VehicleParams
    worlds: dict[str, World]
    gains: dict[str, Gains]

    def fingerprint(self) -> dict:
        """What the files gave, JSON-ready: the vehicle, the gains and a hash of each map,
        so a batch folder can tell when a file changed under it."""
        return {"vehicle": as_plain(self.vehicle),
                "gains": {name: as_plain(gains) for name, gains in self.gains.items()},
                "maps": {name: _world_hash(world) for name, world in self.worlds.items()}}


def _world_hash(world: World) -> str:
    parts = [world.boundary, world.blocks, world.start, world.goal, world.margin]
    digest = hashlib.sha256(repr([None if p is None else np.asarray(p).tolist()
                                  for p in parts]).encode())
    return digest.hexdigest()[:16]


def load_context(spec: BatchSpec) -> BatchContext:
    """Load the vehicle, maps and gains of ``spec``; QuadnavError for a bad file or a
    setting out of range, before any mission flies."""
    vehicle = load_params(spec.fixed.vehicle)
    worlds = {entry.map: load_world(entry.map) for entry in spec.maps}
    gains = {name: load_gains(None if name == DEFAULT_GAINS else name, vehicle.gains)
             for name in spec.gains}
    context = BatchContext(spec.fixed, vehicle, worlds, gains)
    for mission in spec.missions()[:1]:  # every mission's settings are checked alike
        mission_settings(context, mission)
    return context


def spread_factors(mission: MissionSpec) -> tuple[float, float, float]:
    """The factors (mass, thrust coefficient, drag) of the mission's flown vehicle, each
    uniform in [1 - f, 1 + f] for its spread fraction f, drawn from the mission's seed."""
    rng = np.random.default_rng([mission.seed, SPREAD_STREAM])
    draws = rng.uniform(-1.0, 1.0, 3)
    spread = mission.spread
    mass, thrust, drag = (1.0 + f * u for f, u in zip(
        (spread.mass, spread.thrust, spread.drag), draws, strict=True))
    return float(mass), float(thrust), float(drag)


def mission_settings(context: BatchContext, mission: MissionSpec) -> MissionSettings:
    """The settings ``mission`` flies with: the batch's fixed settings and the mission's
    grid values; the plant is the nominal vehicle scaled by :func:`spread_factors`.

    Raises:
        QuadnavError: settings that do not fit together (e.g. a physics rate that is not a
            multiple of the control rate, a spread vehicle that cannot lift itself).
    """
    fixed, vehicle = context.fixed, context.vehicle
    mass, thrust, drag = spread_factors(mission)
    plant = None
    if (mass, thrust, drag) != (1.0, 1.0, 1.0):
        plant = vehicle.replace(mass=vehicle.mass * mass,
                                thrust_coefficient=vehicle.thrust_coefficient * thrust,
                                drag=vehicle.drag * drag,
                                rotor_drag=vehicle.rotor_drag * drag,
                                parasitic_drag=vehicle.parasitic_drag * drag)
    return MissionSettings(
        planner=mission.planner,
        planning=PlannerSettings(time_limit=fixed.time_cap, improve_iterations=fixed.improve,
                                 seed=mission.seed),
        trajectory=TrajectorySettings(method=fixed.method, timing=fixed.timing,
                                      v_max=mission.speed or DEFAULT_V_MAX, a_max=fixed.accel),
        fastest=mission.speed is None,
        vehicle=vehicle,
        gains=context.gains[mission.gains],
        sim=SimSettings(physics_rate=fixed.physics_rate, control_rate=fixed.control_rate,
                        record_rate=default_record_rate(fixed.control_rate),
                        settle_time=fixed.settle, wind=mission.wind, gust_std=mission.gusts,
                        seed=mission.seed),
        plant=plant)


def mission_margin(context: BatchContext, mission: MissionSpec) -> float:
    """The mission's margin, m: its map entry's, else the batch's, else the map's own,
    else 0.2."""
    world = context.worlds[mission.map.map]
    for margin in (mission.map.margin, context.fixed.margin, world.margin):
        if margin is not None:
            return margin
    return DEFAULT_MARGIN


def given_query(context: BatchContext, mission: MissionSpec
                ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The start and goal given for the mission (its map entry's, else the map's own),
    each (3,) m or None when there is none, to be drawn from the seed."""
    world = context.worlds[mission.map.map]
    start = world.start if mission.map.start is None else np.array(mission.map.start)
    goal = world.goal if mission.map.goal is None else np.array(mission.map.goal)
    return start, goal


def mission_problem(context: BatchContext, mission: MissionSpec, body: np.ndarray
                    ) -> PlanningProblem:
    """The mission's checked query for a vehicle whose body has half extents ``body``
    (3,) m. A start or goal that is not given is drawn from the seed: of
    :data:`DRAWN_POINTS` free points of the inflated map, the most distant pair (or the
    point most distant from the given end) that :func:`make_problem` accepts.

    Raises:
        QuadnavError: a bad query (a given point in a block, disconnected ends).
    """
    world = context.worlds[mission.map.map]
    margin = mission_margin(context, mission)
    start, goal = given_query(context, mission)
    if start is not None and goal is not None:
        return make_problem(world, start, goal, margin, body)
    rng = np.random.default_rng([mission.seed, QUERY_STREAM])
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
    raise QuadnavError(f"no start and goal drawn from seed {mission.seed} could be joined: "
                       f"{error}")


def fly_mission_spec(context: BatchContext, mission: MissionSpec) -> Mission:
    """Fly ``mission`` (planning warnings silenced: a batch reports in its table).

    Raises:
        QuadnavError: a bad query or settings (see :func:`mission_problem`).
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)
        settings = mission_settings(context, mission)
        return fly_problem(mission_problem(context, mission, settings.body), settings)


def fly_row(context: BatchContext, mission: MissionSpec) -> dict:
    """The results row of ``mission`` (:func:`~.table.mission_row`). Never raises for the
    mission's own failure: a refused query or setting is a row with ``success`` false and
    the reason in ``error``."""
    start, goal = given_query(context, mission)
    drawn = start is None or goal is None
    try:
        flown = fly_mission_spec(context, mission)
    except QuadnavError as error:
        return mission_row(mission, spread_factors(mission), drawn, None, str(error),
                           start, goal, mission_margin(context, mission))
    return mission_row(mission, spread_factors(mission), drawn, flown)


def warm_up(context: BatchContext) -> None:
    """Load every compiled kernel a mission runs (from numba's cache) by flying a short
    mission through a small built-in world."""
    world = load_world("window:size=4x6x3,walls=1")
    settings = MissionSettings(planning=PlannerSettings(improve_iterations=100),
                               trajectory=TrajectorySettings(v_max=1.0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)
        fly_problem(make_problem(world, None, None, DEFAULT_MARGIN, settings.body), settings)
