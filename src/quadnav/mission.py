"""The whole pipeline, World -> Path -> Trajectory -> Flight: :func:`fly_mission`.

Plan with RRT* (or an OMPL planner, or one of your own), shortcut and smooth the path, make
a minimum-snap trajectory that keeps the margin everywhere but on the legs out of it,
check that the vehicle can fly it (or, instead, build a trajectory class of your own from
the path and sample it: :mod:`quadnav.trajectory.references.plain`), and fly it in
simulation against the real (uninflated) map. :meth:`Mission.metrics` summarises the
outcome for reports and ``metrics.json``, with the margin kept on and off the legs measured exactly.
"""

from __future__ import annotations

import dataclasses
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.config import as_plain
from quadnav.control.contract import Controller
from quadnav.control.gains import Gains
from quadnav.control.registry import (
    DEFAULT_CONTROLLER,
    check_controller_rate,
    controller_gains,
    make_controller,
)
from quadnav.errors import PlanningWarning
from quadnav.planning import PlannerSettings, PlanningProblem, PlanResult, make_problem, plan
from quadnav.planning.refine import refine
from quadnav.planning.result import Progress, path_length
from quadnav.planning.stall import StallRule
from quadnav.plugins import parse_spec
from quadnav.profiling import staged
from quadnav.sim.flight import Ending, Flight
from quadnav.sim.settings import SimSettings
from quadnav.sim.simulate import simulate
from quadnav.trajectory.clearance.space import (
    SafeSpace,
    reference_margins,
    windowed_margins,
    within_window,
)
from quadnav.trajectory.envelope import flyable_trajectory
from quadnav.trajectory.generate import TrajectorySettings
from quadnav.trajectory.model import Trajectory, YawMode
from quadnav.trajectory.references.plain import (
    FlatOutputReference,
    check_ends,
    flat_reference,
    leg_window,
    load_trajectory_class,
)
from quadnav.trajectory.timing.segment_times import DEFAULT_A_MAX, DEFAULT_V_MAX
from quadnav.vehicle.params import VehicleParams, load_params
from quadnav.world.margins import segment_box_margins
from quadnav.world.model import World

#: Cruise speed of a mission, m/s, and its acceleration limit, m/s^2: the trajectory
#: stage's defaults, the same for ``fly``, ``traj`` and the library.
DEFAULT_SPEED = DEFAULT_V_MAX
DEFAULT_ACCELERATION = DEFAULT_A_MAX
#: Search budget of a mission: the stall rule (:mod:`quadnav.planning.stall`), at most this
#: many samples of improvement after the first path, and a wall-time cap in seconds on the
#: whole search. The first path takes as many samples as it needs, so the same seed flies
#: the same flight unless the time cap ends the search.
DEFAULT_IMPROVE = 50_000
DEFAULT_TIME_CAP = 10.0


def _default_planner() -> PlannerSettings:
    return PlannerSettings(improve_iterations=DEFAULT_IMPROVE, stall=StallRule(),
                           time_limit=DEFAULT_TIME_CAP)


def _default_trajectory() -> TrajectorySettings:
    return TrajectorySettings(v_max=DEFAULT_SPEED, a_max=DEFAULT_ACCELERATION)


@dataclass(frozen=True, eq=False)
class MissionSettings:
    """Everything a mission needs besides the map and the query.

    Attributes:
        planner: planner name (``rrtstar`` or ``ompl:NAME``), or a plain function of your
            own, ``module:function`` or ``path/to/file.py:function``
            (:mod:`quadnav.planning.plain`).
        planning: the planner's budget, seed and tuning.
        refine: shortcut and smooth the path before making the trajectory (shortcut only
            for a trajectory class of your own, ``reference``: the fewest straight
            segments, whose corners the class rounds as it will).
        trajectory: generator and limits (``v_max`` is the top speed).
        fastest: ignore the trajectory's speed and acceleration limits and fly as fast as
            the vehicle can follow on the path: its own limits
            (:func:`~quadnav.trajectory.envelope.vehicle_limits`), lowered until every limit
            holds (:func:`~quadnav.trajectory.envelope.flyable_trajectory`; ``--speed max``).
        vehicle: the simulated quadrotor, as the trajectory and the controller know it.
        gains: the controller's own gains (the cascade's
            :class:`~quadnav.control.gains.Gains`, SE(3)'s
            :class:`~quadnav.control.se3.SE3Gains`, a plain-Python controller's inner
            loops' :class:`~quadnav.control.gains.Gains`); None: those tuned for
            ``vehicle``, whichever it is (:attr:`flown_gains`), so that a vehicle never
            flies with another vehicle's gains unless they are given.
        controller: the controller by name or spec
            (:func:`~quadnav.control.registry.make_controller`: ``cascade``, ``se3``, one
            registered, or ``module:NAME`` / ``path/to/file.py:NAME`` with keyword
            arguments, a compiled controller's factory or a plain-Python controller's
            class, loaded and checked here and built afresh for each flight).
        sim: rates, stopping and success rules, disturbances, seed. A control rate too
            slow for the controller's gains on the flown vehicle is refused, one that
            leaves them little margin warned about
            (:func:`~quadnav.control.registry.check_controller_rate`).
        plant: the vehicle that really flies (default: ``vehicle``), e.g. heavier than
            ``vehicle``: the trajectory is made for ``vehicle`` and the controller keeps
            its model, unaware of the difference.
        reference: a trajectory class of your own that replaces the trajectory stage,
            ``module:Class`` or ``path/to/file.py:Class`` with literal keyword arguments
            (:mod:`quadnav.trajectory.references.plain`): built from the refined path (as ``points``
            when it takes them), sampled at the control rate and flown; it must start at
            the start and end at the goal (within ``sim.goal_tolerance``). ``trajectory``
            and ``fastest`` then do not apply. None: quadnav's trajectory stage.
        reference_duration: how long ``reference`` is flown, s (None: as long as it says
            it lasts).
    """

    planner: str = "rrtstar"
    planning: PlannerSettings = field(default_factory=_default_planner)
    refine: bool = True
    trajectory: TrajectorySettings = field(default_factory=_default_trajectory)
    fastest: bool = False
    vehicle: VehicleParams = field(default_factory=load_params)
    gains: Any = None
    controller: str = DEFAULT_CONTROLLER
    sim: SimSettings = field(default_factory=SimSettings)
    plant: VehicleParams | None = None
    reference: str | None = None
    reference_duration: float | None = None

    def __post_init__(self) -> None:
        if self.reference is not None:
            parse_spec(self.reference, "reference")  # QuadnavError for a malformed spec
        # QuadnavError naming the choices for an unknown controller, bad gains or a control
        # rate its loops are unstable at; a plain-Python one is loaded and checked, not
        # built (it is, once per flight)
        check_controller_rate(self.controller, self.vehicle, self.gains,
                              self.sim.control_rate, self.plant)

    @property
    def flown_gains(self) -> Any:
        """The gains the controller flies with: ``gains``, else those tuned for ``vehicle``
        (:func:`~quadnav.control.registry.controller_gains`; None for a controller without
        gains of its own)."""
        if self.gains is not None:
            return self.gains
        return controller_gains(self.controller, self.vehicle)

    def flying_controller(self) -> Controller:
        """The controller, with its gains, for the vehicle as it knows it (``vehicle``)."""
        return make_controller(self.controller, self.vehicle, self.flown_gains)

    @property
    def limit_gains(self) -> Gains:
        """The cascade gains whose saturations (thrust, tilt, rates, speed) bound what the
        trajectory may ask (:func:`~quadnav.trajectory.envelope.vehicle_limits`): the flown gains
        when the cascade flies, else the cascade's tuned for ``vehicle``."""
        gains = self.flown_gains
        return gains if isinstance(gains, Gains) else controller_gains(DEFAULT_CONTROLLER,
                                                                        self.vehicle)

    @property
    def flown_vehicle(self) -> VehicleParams:
        """The vehicle that really flies: ``plant``, else ``vehicle``."""
        return self.plant or self.vehicle

    @property
    def body(self) -> FloatArray:
        """(3,) half extents of the flown vehicle's body along x, y, z, m, as missions fly
        it: what :func:`~quadnav.planning.make_problem` keeps inside the map. At yaw 0, or at
        any heading when the trajectory turns the vehicle to face its travel, or when a
        trajectory class of your own (``reference``) may turn it."""
        if self.trajectory.yaw is YawMode.TRAVEL or self.reference is not None:
            return self.flown_vehicle.half_extents_any_heading()
        return self.flown_vehicle.half_extents()


@dataclass(frozen=True, eq=False)
class Mission:
    """The outcome of every stage.

    Attributes:
        problem: the checked query (world, margin, start, goal).
        plan: the planner's result after refinement (``plan.solved`` False: no path).
        raw_length: path length before refinement, m (inf without a path).
        trajectory: the reference flown (None without a path): quadnav's trajectory, or
            a trajectory class of your own sampled (``settings.reference``).
        flight: the simulated flight (None without a path).
        timings: wall time of each stage, s: ``planning``, ``trajectory``, ``simulation``
            (the closed loop alone; its loading is the flight's ``load_time``).
        settings: what the mission ran with.
    """

    problem: PlanningProblem
    plan: PlanResult
    raw_length: float
    trajectory: Trajectory | FlatOutputReference | None
    flight: Flight | None
    timings: dict[str, float]
    settings: MissionSettings

    @property
    def success(self) -> bool:
        """The flight reached the goal flown to within the goal tolerance, with no contact
        (a block or the floor) and its body inside the map (:func:`flight_succeeded`)."""
        return self.flight is not None and flight_succeeded(self.flight,
                                                             self.settings.sim.goal_tolerance)

    def parameters(self) -> dict:
        """Every setting the mission ran with, JSON-ready: the query, planner, trajectory,
        vehicle, gains and simulation settings, the plant when it is not the vehicle, and a
        trajectory class of your own with how it was sampled."""
        problem = self.problem
        plant = {} if self.settings.plant is None else {"plant": as_plain(self.settings.plant)}
        if self.settings.reference is not None:
            sampled = getattr(self.trajectory, "info", None)
            plant |= {"reference": self.settings.reference,
                      "reference_duration_s": self.settings.reference_duration,
                      "reference_info": None if sampled is None else dict(sampled)}
        return {
            "map": problem.world.name, "start": problem.start.tolist(),
            "goal": problem.goal_asked.tolist(), "margin_m": problem.margin,
            "planner": self.settings.planner, "refine": self.settings.refine,
            "planning": as_plain(self.settings.planning),
            "trajectory": as_plain(self.settings.trajectory),
            "vehicle": as_plain(self.settings.vehicle),
            "gains": as_plain(self.settings.flown_gains),
            "controller": self.settings.controller,
            "simulation": as_plain(self.settings.sim),
        } | plant

    def metrics(self) -> dict:
        """JSON-ready summary, written as ``metrics.json`` (docs/flying.md lists its keys)."""
        problem = self.problem
        return {
            "success": self.success,
            "map": problem.world.name,
            "start": problem.start.tolist(),
            "goal": problem.goal.tolist(),
            "goal_asked": problem.goal_asked.tolist(),
            "margin_m": problem.margin,
            "start_leg_m": path_length(problem.start_leg),
            "goal_leg_m": path_length(problem.goal_leg),
            "planner": self.plan.planner,
            "seed": self.plan.seed,
            "vehicle": self.settings.vehicle.name,
            "speed_m_s": self.settings.trajectory.v_max,
            "path_found": self.plan.solved,
            "path_length_m": self.plan.length if self.plan.solved else None,
            "path_vertices": len(self.plan.path) if self.plan.solved else 0,
            "planning_time_s": self.timings["planning"],
            "search_stopped_by": self.plan.stats.stopped_by,
            "trajectory_time_s": self.timings.get("trajectory"),
            "trajectory_duration_s": self.trajectory.duration if self.trajectory else None,
        } | self.measured

    @cached_property
    def measured(self) -> dict:
        """The flight's part of :meth:`metrics` (:func:`measure_flight`), measured once;
        without a flight, that it neither collided nor reached the goal."""
        if self.trajectory is None or self.flight is None:
            return {"collision": False, "reached_goal": False}
        return measure_flight(self.problem.world, self.trajectory, self.flight,
                              self.settings.sim, self.problem.margin)


@staged("metrics")
def measure_flight(world: World, trajectory: Trajectory | FlatOutputReference, flight: Flight,
                   settings: SimSettings, margin: float) -> dict:
    """The flight's part of :meth:`Mission.metrics`: the margin (per axis, m) kept from the
    real blocks and the boundary, measured exactly, by the trajectory
    (:func:`~quadnav.trajectory.clearance.space.reference_margins`) and by the flight,
    off the legs and on them (None without legs), how much less than the asked ``margin``
    m the flight kept off the legs (:func:`margin_shortfall`) and when it kept the least
    (:func:`least_margin_time`), and :func:`flight_metrics`. The flown track is taken as
    straight between its records, each such stretch measured by its bounding box."""
    off, on = reference_margins(trajectory, world)
    stretches = segment_box_margins(world, flight.position)
    window = trajectory.main_window
    flown_off, flown_on = windowed_margins(flight.t, stretches, window)
    return {"trajectory_margin_m": off, "trajectory_leg_margin_m": on,
            "flight_margin_m": flown_off, "flight_leg_margin_m": flown_on,
            "margin_shortfall_m": margin_shortfall(margin, flown_off),
            "flight_margin_time_s": least_margin_time(flight.t, stretches, window),
            } | flight_metrics(flight, world, settings)


def margin_shortfall(asked: float, kept: float) -> float:
    """How much less than the ``asked`` margin a flight ``kept`` off the legs, m: 0 when it
    kept all of it; any shortfall, however small, is more than 0."""
    return asked - kept if kept < asked else 0.0


def least_margin_time(t: FloatArray, stretches: FloatArray, window: tuple[float, float]
                      ) -> float | None:
    """When a track at times ``t`` (K,) s kept its least margin within ``window`` (off the
    legs): the start, s, of the stretch (of ``stretches`` (K - 1,), m) that kept the least;
    None when no stretch lies within the window."""
    within = within_window(t, window)
    if not within.any():
        return None
    return float(t[:-1][within][np.argmin(stretches[within])])


def flight_succeeded(flight: Flight, goal_tolerance: float) -> bool:
    """Whether the flight ran to the end (no contact with a block, no crash into the floor,
    no leaving the boundary, no divergence), its body never left the map after the start,
    and it ended within ``goal_tolerance`` m of the end of its reference (the goal flown
    to)."""
    return (flight.ending is Ending.COMPLETED and not flight.body_outside
            and flight.final_error <= goal_tolerance)


def failure_reason(mission: Mission) -> str:
    """One line saying why ``mission`` failed: no path (and why), or why its flight failed
    (:func:`flight_failure`)."""
    if mission.flight is None:
        return f"no path: {mission.plan.message}"
    return flight_failure(mission.flight, mission.settings.sim.goal_tolerance)


def flight_failure(flight: Flight, goal_tolerance: float, goal: str = "the goal") -> str:
    """One line saying why a flight failed: a collision, hitting the floor, leaving the map,
    diverging, the body leaving the map, or ending more than ``goal_tolerance`` m from
    ``goal``."""
    if flight.contact_block is not None:
        return (f"collided with block {flight.contact_block} at t = "
                f"{flight.contact_time:.2f} s")
    if flight.ending is Ending.FLOOR:
        return f"hit the floor at {flight.floor_speed:.2f} m/s at t = {flight.contact_time:.2f} s"
    if flight.contact_time is not None:
        return f"{flight.ending.value} at t = {flight.contact_time:.2f} s"
    if flight.body_outside:
        outside = flight.body_outside
        return (f"the body left the map by {100 * outside.depth:.1f} cm for "
                f"{outside.duration:.2f} s from t = {outside.since:.2f} s")
    return (f"ended {100 * flight.final_error:.1f} cm from {goal} (tolerance "
            f"{100 * goal_tolerance:.0f} cm)")


def min_clearance(flight: Flight, world: World) -> float | None:
    """Closest approach of the vehicle's centre to a real block's surface over the
    recorded samples, m (None for a map with no blocks)."""
    if len(world.blocks) == 0:
        return None
    open_world = world.replace(boundary=world.boundary + np.repeat([-1e6, 1e6], 3))
    return float(open_world.clearances(flight.position).min())


def flight_metrics(flight: Flight, world: World, settings: SimSettings) -> dict:
    """The flight's part of :meth:`Mission.metrics`."""
    return {
        "collision": flight.ending is Ending.COLLISION,
        "reached_goal": flight.final_error <= settings.goal_tolerance,
        "ending": flight.ending.value,
        "contact_time_s": flight.contact_time,
        "contact_block": flight.contact_block,
        "floor_touch_speed_m_s": flight.floor_speed,
        "body_outside_m": flight.body_outside.depth,
        "body_outside_time_s": flight.body_outside.duration,
        "body_outside_since_s": flight.body_outside.since,
        "final_error_m": flight.final_error,
        "goal_tolerance_m": settings.goal_tolerance,
        "time_to_goal_s": time_to_goal(flight, settings.goal_tolerance),
        "flight_time_s": flight.duration,
        "rms_tracking_error_m": flight.rms_tracking_error,
        "max_tracking_error_m": flight.max_tracking_error,
        "max_velocity_error_m_s": flight.max_velocity_error,
        "min_clearance_m": min_clearance(flight, world),
        "mixer_saturation": flight.mixer_saturation,
        "rotor_energy_j": flight.rotor_energy,
        "sim_load_time_s": flight.load_time,
        "sim_wall_time_s": flight.wall_time,
        "real_time_factor": flight.duration / flight.wall_time if flight.wall_time else None,
    }


def time_to_goal(flight: Flight, tolerance: float) -> float | None:
    """When ``flight`` came within ``tolerance`` m of its goal to stay, s (the time of the
    first record from which every record is that close), or None when it ended farther
    (then :func:`flight_metrics`' ``reached_goal`` is false, and only then)."""
    far = np.linalg.norm(flight.position - flight.goal, axis=1) > tolerance
    if far[-1]:
        return None
    last = np.flatnonzero(far)
    return float(flight.t[last[-1] + 1 if last.size else 0])


def fly_mission(world: World, start: ArrayLike | None = None, goal: ArrayLike | None = None,
                margin: float | None = None, settings: MissionSettings | None = None,
                planning_progress: Progress | None = None,
                flight_progress: Callable[[float], None] | None = None) -> Mission:
    """Plan, smooth, make a trajectory and fly it.

    Args:
        world: the real map.
        start: (3,) m, or None for the map's own.
        goal: (3,) m, or None for the map's own.
        margin: safety margin, m (None: the map's own, else 0.2:
            :meth:`~quadnav.world.World.margin_for`).
        settings: see :class:`MissionSettings`.
        planning_progress: called with (fraction of the budget, best length m).
        flight_progress: called with the fraction of the flight simulated.

    Raises:
        QuadnavError: a bad query (a start in a block, a goal outside the map, a start
            and goal provably disconnected).
    """
    settings = settings or MissionSettings()
    return fly_problem(make_problem(world, start, goal, world.margin_for(margin), settings.body),
                       settings, planning_progress, flight_progress)


def fly_problem(problem: PlanningProblem, settings: MissionSettings | None = None,
                planning_progress: Progress | None = None,
                flight_progress: Callable[[float], None] | None = None) -> Mission:
    """:func:`fly_mission` for a query already checked by
    :func:`~quadnav.planning.make_problem` (so bad input fails before any work)."""
    settings = settings or MissionSettings()
    warn_if_margin_too_small(problem.margin, settings.vehicle)
    return fly_plan(plan_mission(problem, settings, planning_progress), settings,
                    flight_progress)


def plan_mission(problem: PlanningProblem, settings: MissionSettings,
                 progress: Progress | None = None) -> Mission:
    """The planning stage of :func:`fly_problem`: the path found (and refined), with
    neither trajectory nor flight yet, to fly with :func:`fly_plan`."""
    began = time.perf_counter()
    result = plan(problem, settings.planning, settings.planner, progress)
    raw_length = result.length
    if settings.refine and result.solved:  # a class of your own rounds the corners itself
        result = refine(problem, result, smooth=settings.reference is None)
    timings = {"planning": time.perf_counter() - began}
    return Mission(problem, result, raw_length, None, None, timings, settings)


def fly_plan(planned: Mission, settings: MissionSettings | None = None,
             flight_progress: Callable[[float], None] | None = None) -> Mission:
    """The rest of :func:`fly_problem` after :func:`plan_mission`: the trajectory along
    ``planned``'s path (:func:`make_reference`) and its flight (:func:`fly_reference`),
    with ``settings`` (default: ``planned``'s own; the same planning settings, as the path
    was found with them). An unsolved plan is returned as it is."""
    settings = settings or planned.settings
    if not planned.plan.solved:
        return dataclasses.replace(planned, settings=settings)
    began = time.perf_counter()
    trajectory, settings = make_reference(planned.problem, planned.plan.path, settings)
    return fly_reference(planned, trajectory, settings, time.perf_counter() - began,
                         flight_progress)


@staged("trajectory")
def make_reference(problem: PlanningProblem, path: FloatArray, settings: MissionSettings
                   ) -> tuple[Trajectory | FlatOutputReference, MissionSettings]:
    """The reference flown along ``path`` (N, 3) m, a solved plan's, and ``settings`` with
    the trajectory settings that made it: quadnav's trajectory
    (:func:`~quadnav.trajectory.envelope.flyable_trajectory`, made for ``settings.vehicle`` with
    :attr:`~MissionSettings.limit_gains`), or a trajectory class of your own sampled
    (:func:`path_reference`).

    Raises:
        QuadnavError: the vehicle cannot fly the trajectory (not ``fastest``), or a class
            of your own cannot be built.
    """
    if settings.reference is not None:
        return path_reference(problem, path, settings), settings
    trajectory, chosen = flyable_trajectory(path, settings.trajectory,
                                            SafeSpace(problem.world, problem.margin),
                                            settings.vehicle, settings.limit_gains,
                                            settings.fastest)
    return trajectory, dataclasses.replace(settings, trajectory=chosen)


def fly_reference(planned: Mission, trajectory: Trajectory | FlatOutputReference,
                  settings: MissionSettings, trajectory_seconds: float,
                  flight_progress: Callable[[float], None] | None = None) -> Mission:
    """``trajectory``, made along ``planned``'s path in ``trajectory_seconds`` s of wall
    time (:func:`make_reference`), flown with ``settings``: the whole mission."""
    problem = planned.problem
    flight = simulate(trajectory, settings.flown_vehicle, world=problem.world,
                      settings=settings.sim, progress=flight_progress, model=settings.vehicle,
                      controller=settings.flying_controller())
    timings = {"planning": planned.timings["planning"], "trajectory": trajectory_seconds,
               "simulation": flight.wall_time}
    return Mission(problem, planned.plan, planned.raw_length, trajectory, flight, timings,
                   settings)


def path_reference(problem: PlanningProblem, path: FloatArray, settings: MissionSettings
                   ) -> FlatOutputReference:
    """The trajectory class ``settings.reference`` built from ``path`` (N, 3) m, sampled
    at the control rate for ``settings.reference_duration`` s (or as long as it says),
    with its legs' times (:func:`~quadnav.trajectory.references.plain.leg_window`).

    Raises:
        QuadnavError: a class that cannot be loaded or built (exit 2).
        PluginError: one that raises or returns what cannot be flown, or that does not
            start at the start and end at the goal within the goal tolerance (exit 1).
    """
    chosen = load_trajectory_class(str(settings.reference), with_points=True)
    built = chosen.build(path, problem.world, problem.start, problem.goal)
    reference = flat_reference(built, chosen.text, 1.0 / settings.sim.control_rate,
                               settings.reference_duration)
    check_ends(reference, problem.start, problem.goal, settings.sim.goal_tolerance)
    window = leg_window(reference, problem.free_world, len(problem.start_leg) > 1,
                        len(problem.goal_leg) > 1)
    return dataclasses.replace(reference, window=window)


def warn_if_margin_too_small(margin: float, vehicle: VehicleParams) -> None:
    """Warn when ``margin`` m is less than the half-diagonal of the vehicle's body box,
    the most the body can reach past its centre however it turns."""
    reach = 0.5 * float(np.linalg.norm(vehicle.body_size))
    if margin < reach:
        warnings.warn(f"the {margin:g} m margin cannot hold the {vehicle.name} vehicle's body "
                      f"(it reaches {reach:.3g} m from its centre): a flight that keeps the "
                      "margin may still touch a block", PlanningWarning, stacklevel=2)
