"""Flying a given reference — the course's gain-tuning workflow: :func:`track_reference`.

A reference (a built-in shape or step, samples read from a file, any
:class:`~quadnav.trajectory.references.contract.Reference`) is flown from a hover at its start in
an empty world (:func:`track_world`): its bounding box widened by
:data:`BOUNDARY_SLACK` on every side, with the floor at z = 0 when the reference stays
:data:`FLOOR_CLEARANCE` above it, so that a controller that diverges ends the flight
(``left boundary``), which a gain tuner counts as a failure. A step is recorded at the
control rate, for its step-response metrics (:mod:`quadnav.sim.step_response`).
:meth:`Tracking.metrics` summarises the outcome for reports and ``metrics.json``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from quadnav.config import as_plain
from quadnav.control.registry import (
    DEFAULT_CONTROLLER,
    check_controller_rate,
    controller_gains,
    make_controller,
)
from quadnav.mission import flight_metrics, flight_succeeded
from quadnav.sim.flight import Flight
from quadnav.sim.settings import SimSettings
from quadnav.sim.simulate import simulate
from quadnav.sim.step_response import step_response
from quadnav.trajectory.model import Trajectory
from quadnav.trajectory.references.builtin import StepReference
from quadnav.trajectory.references.contract import Reference
from quadnav.vehicle.params import VehicleParams, load_params
from quadnav.world.model import World

#: How far the world's boundary lies beyond the reference's bounding box on every side, m.
BOUNDARY_SLACK = 1.0
#: Least height of a reference above z = 0 for the world's floor to be at z = 0, m.
FLOOR_CLEARANCE = 0.3
#: Sample interval of the reference when measuring its bounding box, s.
BOX_DT = 0.01
PERCENT = 100.0


def reference_name(reference: Reference) -> str:
    """How reports name ``reference``: its ``name`` (a built-in reference's canonical spec,
    a file reference's path), a :class:`~quadnav.trajectory.model.Trajectory` by its
    method, else its class."""
    name = getattr(reference, "name", None)
    if isinstance(name, str):
        return name
    if isinstance(reference, Trajectory):
        return f"{reference.method} trajectory"
    return type(reference).__name__


def track_world(reference: Reference) -> World:
    """The empty world a reference is flown in: its bounding box (sampled every
    :data:`BOX_DT` s) widened by :data:`BOUNDARY_SLACK` on every side, its lower face at
    z = 0 instead when the reference stays at least :data:`FLOOR_CLEARANCE` above it;
    start and goal where the reference starts and ends (to a picometre); named after the
    reference."""
    points = reference.sample(BOX_DT).position
    low, high = points.min(axis=0) - BOUNDARY_SLACK, points.max(axis=0) + BOUNDARY_SLACK
    if points[:, 2].min() >= FLOOR_CLEARANCE:
        low[2] = 0.0
    start, goal = (np.round(reference.position(t), 12) + 0.0  # round-off (and -0) shown as 0
                   for t in (0.0, reference.duration))
    return World(np.concatenate([low, high]), start=start, goal=goal,
                 name=reference_name(reference))


@dataclass(frozen=True, eq=False)
class Tracking:
    """A reference flown.

    Attributes:
        reference: what was flown.
        world: the empty world it was flown in (:func:`track_world`).
        flight: the flight.
        vehicle: the simulated quadrotor.
        gains: the controller's own gains (None for a controller without any).
        settings: the simulation settings flown with (a step's record rate raised to the
            control rate).
        controller: the controller's name or spec (``cascade``, ``se3``, ...).
    """

    reference: Reference
    world: World
    flight: Flight
    vehicle: VehicleParams
    gains: Any
    settings: SimSettings
    controller: str = DEFAULT_CONTROLLER

    @property
    def name(self) -> str:
        """The reference's name (:func:`reference_name`)."""
        return reference_name(self.reference)

    @property
    def success(self) -> bool:
        """The flight ran to the end without leaving the world or diverging, and ended
        within the goal tolerance of the reference's end."""
        return flight_succeeded(self.flight, self.settings.goal_tolerance)

    def parameters(self) -> dict:
        """Every setting the reference was flown with, JSON-ready: the reference (and how
        a file was read), the world's boundary, vehicle, gains and simulation settings."""
        return {
            "reference": self.name,
            "reference_info": dict(getattr(self.reference, "info", {})),
            "boundary": self.world.boundary.tolist(),
            "vehicle": as_plain(self.vehicle),
            "gains": as_plain(self.gains),
            "controller": self.controller,
            "simulation": as_plain(self.settings),
        }

    def metrics(self) -> dict:
        """JSON-ready summary: success, the reference and its duration, where it starts
        and ends, the vehicle, the flight's metrics
        (:func:`~quadnav.mission.flight_metrics`: ending, tracking errors, final error,
        mixer saturation, ...) and, for a step, :meth:`step_metrics`."""
        reference = self.reference
        return {
            "success": self.success,
            "reference": self.name,
            "reference_duration_s": reference.duration,
            "start": self.world.start.tolist(),
            "goal": self.world.goal.tolist(),
            "vehicle": self.vehicle.name,
        } | flight_metrics(self.flight, self.world, self.settings) | self.step_metrics()

    def step_metrics(self) -> dict:
        """For a step reference (:class:`~quadnav.trajectory.references.builtin.StepReference`
        with a jump): its axis, size (m) and time (s), and the response
        (:func:`~quadnav.sim.step_response.step_response`): ``overshoot_percent``,
        ``rise_time_s`` (10-90 %), ``settling_time_s`` (2 %, from the step time; None if
        not settled) and ``steady_state_error_m``; empty otherwise, or if the flight
        stopped before the step."""
        step, flight = self.reference, self.flight
        if not (isinstance(step, StepReference) and step.is_step) or flight.t[-1] < step.at:
            return {}
        response = step_response(flight.t, flight.position, step.start, step.target, step.at)
        axis = int(np.argmax(np.abs(step.jump)))
        return {
            "step_axis": "xyz"[axis],
            "step_size_m": float(step.jump[axis]),
            "step_time_s": step.at,
            "overshoot_percent": PERCENT * response.overshoot,
            "rise_time_s": response.rise_time,
            "settling_time_s": response.settling_time,
            "steady_state_error_m": response.steady_state_error,
        }


def step_summary(metrics: dict) -> str:
    """A step's response (:meth:`Tracking.step_metrics`, e.g. from metrics.json) in
    words: size and axis, overshoot, rise and settling times, steady-state error."""
    def seconds(value: float | None) -> str:
        return "-" if value is None else f"{value:.2f} s"

    return (f"step {metrics['step_size_m']:g} m along {metrics['step_axis']}: overshoot "
            f"{metrics['overshoot_percent']:.2f} %, rise (10-90 %) "
            f"{seconds(metrics['rise_time_s'])}, settling (2 %) "
            f"{seconds(metrics['settling_time_s'])}, steady-state error "
            f"{100 * metrics['steady_state_error_m']:.2f} cm")


def track_reference(reference: Reference, vehicle: VehicleParams | None = None,
                    gains: Any = None, settings: SimSettings | None = None,
                    progress: Callable[[float], None] | None = None,
                    controller: str = DEFAULT_CONTROLLER) -> Tracking:
    """Fly ``reference`` in its :func:`track_world` and measure how well it was tracked.

    Args:
        reference: what to fly (e.g. from
            :func:`~quadnav.trajectory.references.builtin.load_reference`).
        vehicle: the simulated quadrotor (default: the ``tello`` preset).
        gains: the controller's own gains (default: those tuned for the vehicle,
            :func:`~quadnav.control.registry.controller_gains`).
        settings: rates, settling time, goal tolerance, disturbances, seed; a step is
            recorded at the control rate whatever the record rate.
        progress: called with the fraction of the flight simulated.
        controller: the controller by name or spec
            (:func:`~quadnav.control.registry.make_controller`).

    Raises:
        QuadnavError: a flight too long for the rates (see
            :func:`~quadnav.sim.simulate.flight_steps`), or a control rate too slow for
            the controller's gains (:func:`~quadnav.control.registry.check_controller_rate`).
    """
    vehicle = vehicle or load_params()
    if gains is None:
        gains = controller_gains(controller, vehicle)
    settings = settings or SimSettings()
    if isinstance(reference, StepReference) and reference.is_step:
        settings = settings.replace(record_rate=settings.control_rate)
    world = track_world(reference)
    check_controller_rate(controller, vehicle, gains, settings.control_rate)
    flown_by = make_controller(controller, vehicle, gains)
    flight = simulate(reference, vehicle, world=world, settings=settings, progress=progress,
                      controller=flown_by)
    return Tracking(reference, world, flight, vehicle, gains, settings, controller)
