"""A quadrotor kinodynamic plan flown closed loop, measured as ``quadnav fly`` measures.

A plan of :func:`~quadnav.kinodynamic.quadrotor.plan_quadrotor` holds each sampled control
(roll, pitch, thrust) for its duration, so the point mass moves with a constant
acceleration on each: its positions are exactly a piecewise quadratic of time.
:func:`plan_trajectory` writes them as a :class:`~quadnav.trajectory.model.Trajectory`
(a degree-2 PPoly through the planned states, the plan's own positions and velocities at
every break). The plan ends with its closing stop, planned and checked against the map
like every other motion of it, at rest exactly at the goal (and, for a goal inside the
margin, with the leg into it), so the trajectory ends there too.
:func:`fly_kino_plan` flies that trajectory through
:func:`~quadnav.sim.simulate.simulate` with any controller (a name or a spec), in the real map
with its exact contact checks, and measures it as a ``fly`` mission is measured
(:func:`~quadnav.mission.measure_flight`: tracking errors, the margin kept by the
trajectory and by the flight, the rotors' energy), so the two pipelines compare on
success, time and energy. The flight is judged against the goal asked for: it reached the
goal when it ended within the goal tolerance of it, by default the planner's goal radius.

The acceleration steps where one control follows another, which a vehicle can only
follow after its attitude has turned (about 80 ms for the Tello's attitude loop), so the
tracking error of a plan is larger than that of a smooth trajectory at the same speed.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from scipy.interpolate import PPoly

from quadnav.config import as_plain
from quadnav.control.registry import (
    DEFAULT_CONTROLLER,
    check_controller_rate,
    controller_gains,
    make_controller,
)
from quadnav.errors import QuadnavError
from quadnav.kinodynamic.pointmass import SampledQuadrotor
from quadnav.kinodynamic.result import KinoResult
from quadnav.kinodynamic.settings import KinoSettings
from quadnav.mission import flight_succeeded, measure_flight
from quadnav.planning.result import path_length
from quadnav.sim.flight import Flight
from quadnav.sim.settings import SimSettings
from quadnav.sim.simulate import simulate
from quadnav.trajectory.model import Trajectory, YawMode
from quadnav.vehicle.params import VehicleParams, load_params
from quadnav.world.model import World
from quadnav.world.placement import format_point

#: ``Trajectory.method`` of a kinodynamic plan.
METHOD = "kinodynamic"
#: How far, m, the plan may end from the goal of the map flown, and how fast, m/s (the
#: planner ends it exactly there, at rest).
END_TOLERANCE = 1e-9


def plan_trajectory(result: KinoResult, model: SampledQuadrotor) -> Trajectory:
    """The solved plan ``result`` (states (K, 6) position m and velocity m/s, ending at
    rest) as a piecewise quadratic trajectory: on each control, ``p + v t + a t^2 / 2``
    with the constant acceleration that takes the state's velocity to the next one's. Its
    breaks are the planned states' times; the yaw is the model's fixed one; the leg out of
    the margin (``result.leg_controls``) and the leg into it
    (``result.goal_leg_controls``) are marked as the trajectory's legs.

    Raises:
        QuadnavError: no plan, or one that does not end at rest.
    """
    if not result.solved:
        raise QuadnavError(f"no plan to fly: {result.message}")
    positions, velocities, durations = result.states[:, :3], result.states[:, 3:], result.durations
    if np.linalg.norm(velocities[-1]) > END_TOLERANCE:
        raise QuadnavError(f"the plan ends at {format_point(positions[-1])} moving at "
                           f"{np.linalg.norm(velocities[-1]):.2f} m/s; a plan to fly must "
                           "end at rest")
    accelerations = np.diff(velocities, axis=0) / durations[:, None]
    coefficients = np.stack([0.5 * accelerations, velocities[:-1], positions[:-1]])
    breaks = np.concatenate([[0.0], np.cumsum(durations)])
    closing = slice(len(durations) - result.closing_controls - result.goal_leg_controls, None)
    return Trajectory(PPoly(coefficients, breaks), positions, METHOD,
                      yaw_mode=YawMode.CONSTANT, yaw0=model.yaw,
                      info={"controls": len(durations),
                            "stop_s": float(durations[closing].sum())},
                      leg_segments=(result.leg_controls, result.goal_leg_controls))


@dataclass(frozen=True, eq=False)
class KinoFlight:
    """A kinodynamic plan and its closed-loop flight.

    Attributes:
        world: the map flown, with the start, goal and margin of the plan.
        result: the plan (solved).
        model: the point mass it was planned for.
        search: the planner's settings.
        trajectory: the plan as flown (:func:`plan_trajectory`).
        flight: the simulated flight.
        vehicle: the simulated quadrotor.
        gains: the controller's own gains (None for a controller without any).
        controller: the controller's name or spec.
        settings: the simulation's settings.
    """

    world: World
    result: KinoResult
    model: SampledQuadrotor
    search: KinoSettings
    trajectory: Trajectory
    flight: Flight
    vehicle: VehicleParams
    gains: Any
    controller: str
    settings: SimSettings

    @property
    def success(self) -> bool:
        """The flight ran to the end with no contact, its body inside the map, and ended
        within ``settings.goal_tolerance`` of the goal asked for, ``world.goal`` (where the
        plan ends: :func:`fly_kino_plan` checks it); :func:`~quadnav.mission.flight_succeeded`."""
        return flight_succeeded(self.flight, self.settings.goal_tolerance)

    def metrics(self) -> dict:
        """JSON-ready summary, with the keys of a ``fly`` run's ``metrics.json`` that
        apply (no geometric path: ``path_length_m`` is the planned flight's length)."""
        world, result, trajectory = self.world, self.result, self.trajectory
        positions = result.states[:, :3]
        return {
            "success": self.success,
            "map": world.name,
            "start": world.start.tolist(),
            "goal": world.goal.tolist(),
            "margin_m": world.margin,
            "planner": f"kinodynamic {result.planner}",
            "seed": result.seed,
            "vehicle": self.vehicle.name,
            "controller": self.controller,
            "speed_m_s": self.model.speed_limit,
            "path_found": True,
            "path_length_m": path_length(positions),
            "path_vertices": len(positions),
            "planning_time_s": result.seconds,
            "plan_duration_s": result.duration,
            "stop_s": trajectory.info["stop_s"],
            "trajectory_duration_s": trajectory.duration,
            "goal_distance_m": float(np.linalg.norm(self.flight.position[-1] - world.goal)),
        } | self.measured

    @cached_property
    def measured(self) -> dict:
        """The flight's part of :meth:`metrics` (:func:`~quadnav.mission.measure_flight`:
        the margins measured exactly, the tracking statistics), measured once."""
        return measure_flight(self.world, self.trajectory, self.flight, self.settings,
                              self.world.margin or 0.0)

    def parameters(self) -> dict:
        """Every setting the plan and the flight ran with, JSON-ready."""
        return {
            "map": self.world.name, "start": self.world.start.tolist(),
            "goal": self.world.goal.tolist(), "margin_m": self.world.margin,
            "planner": f"kinodynamic {self.result.planner}",
            "kinodynamic": as_plain(self.search), "model": as_plain(self.model),
            "vehicle": as_plain(self.vehicle), "gains": as_plain(self.gains),
            "controller": self.controller, "simulation": as_plain(self.settings),
        }


def fly_kino_plan(world: World, result: KinoResult, model: SampledQuadrotor,
                  search: KinoSettings, vehicle: VehicleParams | None = None,
                  gains: Any = None, settings: SimSettings | None = None,
                  controller: str = DEFAULT_CONTROLLER,
                  progress: Callable[[float], None] | None = None) -> KinoFlight:
    """Fly the solved plan ``result`` closed loop (see the module docstring).

    Args:
        world: the real map, with the plan's start, goal and margin.
        result: a solved quadrotor plan.
        model: the point mass it was planned for.
        search: the planner's settings (recorded).
        vehicle: the simulated quadrotor (default: the ``tello`` preset, the 80 g vehicle
            the default model stands for).
        gains: the controller's own gains (default: those tuned for the vehicle,
            :func:`~quadnav.control.registry.controller_gains`).
        settings: rates, goal tolerance, disturbances, seed (default: the defaults with
            the goal tolerance ``search.goal_radius``).
        controller: a controller's name or spec
            (:func:`~quadnav.control.registry.make_controller`).
        progress: called with the fraction of the flight simulated.

    Raises:
        QuadnavError: no plan, one that does not end at rest at ``world.goal``, or a
            control rate too slow for the controller's gains
            (:func:`~quadnav.control.registry.check_controller_rate`).
    """
    vehicle = vehicle or load_params()
    if gains is None:
        gains = controller_gains(controller, vehicle)
    settings = settings or SimSettings(goal_tolerance=search.goal_radius)
    trajectory = plan_trajectory(result, model)
    end = trajectory.position(trajectory.duration)
    if world.goal is None or np.linalg.norm(end - world.goal) > END_TOLERANCE:
        raise QuadnavError(f"the plan ends at {format_point(end)}, not at the goal "
                           f"{'(none)' if world.goal is None else format_point(world.goal)} "
                           f"of {world.name}")
    check_controller_rate(controller, vehicle, gains, settings.control_rate)
    flown_by = make_controller(controller, vehicle, gains)
    flight = simulate(trajectory, vehicle, world=world, settings=settings, progress=progress,
                      controller=flown_by)
    return KinoFlight(world, result, model, search, trajectory, flight, vehicle, gains,
                      controller, settings)

