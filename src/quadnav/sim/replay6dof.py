"""Fly a quadrotor kinodynamic plan open loop through the full 6-DOF vehicle dynamics.

:func:`replay_6dof` holds each planned control ``(phi, theta, T)`` for its duration as a
setpoint of quadnav's inner loops: the attitude ``R = Rz(psi) Ry(theta) Rx(phi)`` (the
convention of :mod:`~quadnav.kinodynamic.pointmass`, ``psi`` the model's fixed yaw) and
the collective thrust ``T``, fed to :func:`~quadnav.control.cascade.attitude_control`
(attitude P, body-rate PID, mixer, motor commands) and
:func:`~quadnav.vehicle.dynamics.rk4_step` (rigid body, rotor lag), both every
:data:`~quadnav.kinodynamic.quadrotor.REPLAY_STEP` = 1 ms. Nothing feeds the position or
the velocity back: the vehicle only turns to each attitude and pushes with each thrust.

Matching the planner's point-mass model:

* the thrust is scaled by ``params.mass / model.mass``, so the vehicle gets the
  accelerations the plan assumes even when its mass differs from the model's (the
  gravities must be equal);
* the point mass has no drag, so the vehicle to fly is :func:`replay_vehicle`, the
  ``tello`` preset without drag (with the Tello's drag, 0.04 N/(m/s) on an 80 g body,
  the replay ends 17-25 m off on the plans below). The ``rbe595`` preset, whose inertia
  is about 100 times a real 80 g vehicle's, turns far too slowly to follow the plans:
  its replay ends 160-580 m off;
* the flight starts at the plan's first position and velocity, already at the first
  control's attitude with the rotors spinning for its thrust (the planner assumes the
  attitude is there at once);
* the inner loops lag each step of their setpoint, while the point mass switches at
  once. :func:`response_delays` measures the equivalent delay of each loop on a short
  step flight (the integral of one minus its normalised step response: 82 ms for the
  Tello's attitude, 21 ms for its collective thrust); each attitude and each thrust is
  then issued that much early, so the impulse the vehicle receives across a switch is
  the planned one to first order. On the plans below this lead cuts the largest
  deviation from 3.6-23 m to 1.7-9.1 m.

Tolerance. Open loop, small errors of each attitude transition (the attitude swings along
a great circle while the point mass switches between thrust vectors; the yaw wanders by
up to 0.015 rad) add up to a velocity error that grows like a random walk with a slight
bias, so the position deviates roughly like ``t^1.5``. The replayed position at time
``t`` stays within :func:`replay_6dof_tolerance` ``= 0.15 m * (t / 1 s)^1.5`` of the
planned one: 0.05 m after 0.5 s, 0.15 m after 1 s, 1.7 m after 5 s, 4.7 m after 10 s,
25 m after 30 s. Measured at the planned states on 29 plans (those of seeds 0-11 of the
tests' problems in the ``forest``, ``window`` and course ``map1`` worlds that reach the
goal: 23-34 s flights of 31-42 m): at most ``0.075 m * (t / 1 s)^1.5``; 0.08-0.82 m
after 5 s, 0.31-1.95 m after 10 s and 1.7-9.1 m at the end. The bound keeps a margin of
2 over those figures. The exact point-mass :func:`~quadnav.kinodynamic.quadrotor.replay`
remains the check of the planner's own propagation (to 1e-9).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.control.cascade import GainArrays, attitude_control, gain_arrays, new_memory
from quadnav.control.gains import Gains
from quadnav.errors import QuadnavError
from quadnav.kinodynamic.pointmass import SampledQuadrotor
from quadnav.kinodynamic.quadrotor import REPLAY_STEP
from quadnav.vehicle import quaternion
from quadnav.vehicle.dynamics import (
    ATTITUDE,
    ROTORS,
    STATE_SIZE,
    VehicleArrays,
    rk4_step,
    vehicle_arrays,
)
from quadnav.vehicle.params import VehicleParams, load_params

#: Growth of the tolerance, m per s^1.5: the replay stays within ``DRIFT_RATE t^1.5``.
DRIFT_RATE = 0.15
#: Tilt step, rad, and thrust step, fraction of the weight, of :func:`response_delays`.
STEP_TILT = 0.2
STEP_THRUST = 0.3
#: How long :func:`response_delays` watches each step response, s.
STEP_SECONDS = 1.0


def replay_vehicle() -> VehicleParams:
    """The vehicle to fly plans of the default (Tello-class) :class:`SampledQuadrotor`
    with, as ``quadnav kino quadrotor`` does: the ``tello`` preset without drag (the
    planner's point mass has none)."""
    return load_params("tello").replace(name="tello without drag", drag=np.zeros(3))


def replay_6dof_tolerance(t: ArrayLike) -> FloatArray:
    """Largest deviation, m, of the 6-DOF replay from the planned position at times ``t``
    (...,) s from the start: ``DRIFT_RATE t^1.5`` (see the module docstring)."""
    return DRIFT_RATE * np.asarray(t, dtype=np.float64) ** 1.5


def replay_6dof(model: SampledQuadrotor, params: VehicleParams, start_state: ArrayLike,
                controls: ArrayLike, durations: ArrayLike, gains: Gains | None = None,
                dt: float = REPLAY_STEP, leads: tuple[float, float] | None = None
                ) -> tuple[FloatArray, FloatArray]:
    """Fly a control sequence open loop through the 6-DOF dynamics (module docstring).

    Args:
        model: the point-mass model the plan was made for (its mass, gravity and yaw).
        params: the vehicle flown, e.g. :func:`replay_vehicle`; no floor, no obstacles.
        start_state: (6,) position m and velocity m/s.
        controls: (K, 3) ``(phi rad, theta rad, T N)``, thrust for ``model.mass``.
        durations: (K,) s each control is held.
        gains: the inner loops' gains; default :class:`~quadnav.control.gains.Gains`.
        dt: largest step of the inner loops and the integrator, s, > 0.
        leads: how early each attitude and each thrust is issued, s, ``(attitude,
            thrust)``; ``None``: :func:`response_delays` of the vehicle; ``(0, 0)``: at
            the planned times.

    Returns:
        ``(t, states)``: times (N,) s from 0 and vehicle states (N, 17) (layout of
        :mod:`quadnav.vehicle.dynamics`). The planned states' times,
        ``[0, cumsum(durations)]``, are among ``t`` exactly.

    Raises:
        QuadnavError: a step that is not > 0, or gravities that differ.
    """
    if not (math.isfinite(dt) and dt > 0):
        raise QuadnavError(f"replay step must be > 0 s, got {dt}")
    if not math.isclose(model.gravity, params.gravity):
        raise QuadnavError(f"the model's gravity ({model.gravity:g} m/s^2) differs from the "
                           f"vehicle's ({params.gravity:g} m/s^2)")
    gains = gains or Gains()
    u = np.asarray(controls, dtype=np.float64).reshape(-1, 3)
    durations = np.asarray(durations, dtype=np.float64).reshape(len(u))
    attitude_lead, thrust_lead = response_delays(params, gains, dt) if leads is None else leads
    if len(u) == 0:  # nothing to fly: hover at the start for no time
        u = np.array([[0.0, 0.0, model.hover_thrust]])
    attitudes = np.array([quaternion.from_matrix(r) for r in _attitude_matrices(model, u)])
    thrusts = u[:, 2] * (params.mass / model.mass)
    times, steps = _time_grid(durations, dt)
    starts = np.concatenate([[0.0], np.cumsum(durations)[:-1]])
    state = np.zeros(STATE_SIZE)
    state[:6] = start_state
    state[ATTITUDE] = attitudes[0]
    state[ROTORS] = min(math.sqrt(max(thrusts[0], 0.0) / (4 * params.thrust_coefficient)),
                        params.rotor_speed_max)
    states = _fly(state, new_memory(), attitudes, thrusts,
                  _active(starts - attitude_lead, times[:-1], steps),
                  _active(starts - thrust_lead, times[:-1], steps),
                  steps, gain_arrays(gains), vehicle_arrays(params))
    return times, states


def response_delays(params: VehicleParams, gains: Gains | None = None,
                    dt: float = REPLAY_STEP) -> tuple[float, float]:
    """Equivalent delays ``(attitude, thrust)``, s, of the vehicle's closed inner loops.

    From a hover, one flight steps the attitude setpoint by :data:`STEP_TILT` in pitch,
    another the collective thrust by :data:`STEP_THRUST` times the weight; each delay is
    the integral over :data:`STEP_SECONDS` of one minus the response (the tilt, the rotors'
    total thrust) normalised by the step. A lag with that delay and no steady error
    passes a step's whole impulse, only that much later.
    """
    model = SampledQuadrotor(mass=params.mass, gravity=params.gravity)
    hover = model.hover_thrust
    delays = []
    for step in ([0.0, STEP_TILT, hover], [0.0, 0.0, (1 + STEP_THRUST) * hover]):
        times, states = replay_6dof(model, params, np.zeros(6), [[0.0, 0.0, hover], step],
                                    [dt, STEP_SECONDS], gains, dt, leads=(0.0, 0.0))
        after = np.searchsorted(times, dt)
        if step[1]:  # pitch of the attitude (w, 0, y, 0)
            response = 2 * np.arctan2(states[after:, 8], states[after:, 6]) / STEP_TILT
        else:
            total = params.thrust_coefficient * np.sum(states[after:, ROTORS] ** 2, axis=1)
            response = (total - hover) / (STEP_THRUST * hover)
        lag = 1 - response
        delays.append(float(np.sum(0.5 * np.diff(times[after:]) * (lag[:-1] + lag[1:]))))
    return delays[0], delays[1]


def _attitude_matrices(model: SampledQuadrotor, controls: FloatArray) -> FloatArray:
    """``Rz(psi) Ry(theta) Rx(phi)`` (K, 3, 3) of controls (K, 3) at the model's yaw."""
    phi, theta = controls[:, 0], controls[:, 1]
    cf, sf, ct, st = np.cos(phi), np.sin(phi), np.cos(theta), np.sin(theta)
    one, zero = np.ones_like(phi), np.zeros_like(phi)
    rx = np.stack([one, zero, zero, zero, cf, -sf, zero, sf, cf], -1).reshape(-1, 3, 3)
    ry = np.stack([ct, zero, st, zero, one, zero, -st, zero, ct], -1).reshape(-1, 3, 3)
    c, s = math.cos(model.yaw), math.sin(model.yaw)
    rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return rz @ ry @ rx


def _time_grid(durations: FloatArray, dt: float) -> tuple[FloatArray, FloatArray]:
    """Times (N,) s and steps (N - 1,) s: each duration cut into ``ceil(duration / dt)``
    equal steps, so every planned state's time is among the times exactly."""
    times, steps = [np.zeros(1)], []
    begin = 0.0
    for duration in durations:
        count = max(1, math.ceil(duration / dt))
        times.append(begin + duration * np.arange(1, count + 1) / count)
        steps.append(np.full(count, duration / count))
        begin += duration
    return np.concatenate(times), np.concatenate([np.zeros(0), *steps])


def _active(switches: FloatArray, step_starts: FloatArray, steps: FloatArray
            ) -> np.ndarray:
    """Index (N - 1,) of the control in force on each step: the last whose switch time
    (K,) s is at most the step's start (N - 1,) s, to the nearest half step."""
    index = np.searchsorted(switches, step_starts + 0.5 * steps, side="right") - 1
    return np.clip(index, 0, len(switches) - 1).astype(np.int64)


@njit(cache=True)
def _fly(state: np.ndarray, memory: np.ndarray, attitudes: np.ndarray, thrusts: np.ndarray,
         attitude_index: np.ndarray, thrust_index: np.ndarray, steps: np.ndarray,
         g: GainArrays, v: VehicleArrays) -> np.ndarray:
    """States (N, 17) from ``state`` (17,) over ``steps`` (N - 1,) s, step ``i`` asking the
    inner loops for attitude ``attitudes[attitude_index[i]]`` (K, 4) and collective thrust
    ``thrusts[thrust_index[i]]`` (K,) N. Updates ``state`` and ``memory`` in place."""
    out = np.empty((steps.shape[0] + 1, state.shape[0]))
    out[0] = state
    no_force = np.zeros(3)
    for i in range(steps.shape[0]):
        commands = attitude_control(memory, state, attitudes[attitude_index[i]],
                                    thrusts[thrust_index[i]], 0.0, g, v, steps[i])
        rk4_step(state, commands, v, no_force, steps[i], -np.inf)
        out[i + 1] = state
    return out

