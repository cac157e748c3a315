"""Fly a reference in simulation: :func:`simulate`.

The reference (a :class:`~quadnav.trajectory.references.contract.Reference`: a trajectory, a
built-in shape or samples read from a file) is sampled once at the control rate into a
reference table (position, velocity, acceleration, yaw, yaw rate; held at the end during
the settling time); the wind, gusts and sensor noise are drawn up front from
``settings.seed``; then the compiled loop (:mod:`quadnav.sim.loop`) runs the whole flight
in one call, or, when there is a ``progress`` callback, in chunks of :data:`CHUNK_SECONDS`
of flight, calling it in between (each call of the loop costs its argument handling, so
the chunks are long). The loop is first called for
no step, which loads it (numba's dispatch: on a process's first flight, a load from numba's
cache or a compile), so that its one-off cost is timed apart from the flight's
(:attr:`~quadnav.sim.flight.Flight.load_time`, :attr:`~quadnav.sim.flight.Flight.wall_time`).

Python at each control step: a plain-Python controller (its
:attr:`~quadnav.control.contract.Controller.python` side) or a wind model
(:attr:`~quadnav.sim.settings.SimSettings.wind_model`) needs Python before every control
step, so the compiled loop then runs one control step per call (:func:`python_steps`):
first the wind at the vehicle's position, then the controller's ``update`` on the measured
state (noise and all, as the compiled step sees it), then the step itself, with the
disturbances, the record, the checks and the metrics the same as ever. The reference's jerk
and snap, which a Python controller is given, are its own ``jerk(t)`` and ``snap(t)`` where
it has them (a :class:`~quadnav.trajectory.model.Trajectory`), else finite differences of
the sampled acceleration. numpy's and Python's global random generators are seeded with
``settings.seed`` before such a flight, so that a plug-in drawing from them (rotorpy's
Dryden gusts) flies the same flight from the same seed.
"""

from __future__ import annotations

import random
import time
from collections.abc import Callable

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.control.contract import (
    REFERENCE_ACCELERATION,
    REFERENCE_POSITION,
    REFERENCE_YAW,
    Controller,
)
from quadnav.control.gains import Gains
from quadnav.control.registry import DEFAULT_CONTROLLER, make_controller
from quadnav.limits import MAX_CONTROL_STEPS, MAX_PHYSICS_STEPS, check_count, check_duration
from quadnav.profiling import staged
from quadnav.sim import loop
from quadnav.sim.excursion import Excursion, body_excursion
from quadnav.sim.flight import Ending, Flight
from quadnav.sim.settings import SimSettings
from quadnav.sim.wind import load_wind
from quadnav.trajectory.references.contract import Reference
from quadnav.vehicle.dynamics import (
    ATTITUDE,
    POSITION,
    ROTORS,
    STATE_SIZE,
    hover_state,
    vehicle_arrays,
)
from quadnav.vehicle.params import VehicleParams, load_params
from quadnav.world.model import World

#: Simulated seconds per call of the compiled loop when progress is reported.
CHUNK_SECONDS = 1.0
_ENDINGS = {loop.COLLISION: Ending.COLLISION, loop.LEFT_BOUNDARY: Ending.LEFT_BOUNDARY,
            loop.DIVERGED: Ending.DIVERGED, loop.FLOOR: Ending.FLOOR}


def flight_steps(duration: float, settings: SimSettings) -> int:
    """Control steps of a flight of a ``duration`` s trajectory and the settling time.

    Raises:
        QuadnavError: a trajectory over :data:`~quadnav.limits.MAX_DURATION`, or more
            than :data:`~quadnav.limits.MAX_CONTROL_STEPS` control steps or
            :data:`~quadnav.limits.MAX_PHYSICS_STEPS` physics steps; the message says
            which flags lower them.
    """
    check_duration(duration, "fly faster (--speed)")
    flight = duration + settings.settle_time
    what = f"a {flight:.6g} s flight (trajectory and settling time, --settle)"
    steps = int(np.ceil(flight * settings.control_rate - 1e-9)) + 1
    check_count(steps, MAX_CONTROL_STEPS,
                f"{what} at a control rate of {settings.control_rate:g} Hz gives control steps",
                "lower --control-rate or --settle, or fly faster (--speed)")
    check_count(steps * settings.substeps, MAX_PHYSICS_STEPS,
                f"{what} at a physics rate of {settings.physics_rate:g} Hz gives physics steps",
                "lower --physics-rate or --settle, or fly faster (--speed)")
    return steps


def reference_table(trajectory: Reference, dt: float, steps: int) -> FloatArray:
    """(steps, 11) reference rows at times ``k dt``: position, velocity, acceleration,
    yaw, yaw rate (the reference's ``yaw_rate(t)`` when it has one, else the yaw's finite
    difference)."""
    t = np.arange(steps) * dt
    yaw = np.unwrap(np.broadcast_to(trajectory.yaw(t), t.shape))
    rate = getattr(trajectory, "yaw_rate", None)
    yaw_rate = (np.broadcast_to(rate(t), t.shape) if rate is not None
                else np.gradient(yaw, dt) if steps > 1 else np.zeros(steps))
    return np.column_stack([trajectory.position(t), trajectory.velocity(t),
                            trajectory.acceleration(t), yaw, yaw_rate])


def jerk_snap_table(trajectory: Reference, dt: float, steps: int,
                    references: FloatArray) -> FloatArray:
    """(steps, 6) jerk m/s^3 and snap m/s^4 at times ``k dt``: the reference's own
    ``jerk(t)`` and ``snap(t)`` where it has both, else finite differences of the
    acceleration columns of its ``references`` table (steps, 11)."""
    t = np.arange(steps) * dt
    if callable(getattr(trajectory, "jerk", None)) and callable(getattr(trajectory, "snap",
                                                                        None)):
        return np.column_stack([trajectory.jerk(t), trajectory.snap(t)])
    if steps < 2:
        return np.zeros((steps, 6))
    jerk = np.gradient(references[:, REFERENCE_ACCELERATION], dt, axis=0)
    return np.column_stack([jerk, np.gradient(jerk, dt, axis=0)])


def _disturbances(settings: SimSettings, steps: int, dt: float) -> tuple[FloatArray, FloatArray]:
    """External forces (steps, 3) N and measurement noise (steps, 12), from the seed."""
    rng = np.random.default_rng(settings.seed)
    forces = np.tile(settings.wind, (steps, 1))
    if settings.gust_std > 0:
        per_gust = max(1, round(settings.gust_period / dt))
        gusts = rng.normal(0.0, settings.gust_std, ((steps + per_gust - 1) // per_gust, 3))
        forces += np.repeat(gusts, per_gust, axis=0)[:steps]
    noise = np.zeros((steps, 12))
    if settings.noisy:
        scale = np.repeat([settings.position_noise, settings.velocity_noise,
                           settings.attitude_noise, settings.gyro_noise], 3)
        noise = rng.normal(0.0, 1.0, (steps, 12)) * scale
    return forces, noise


@staged("simulation")
def simulate(trajectory: Reference, params: VehicleParams | None = None,
             gains: Gains | None = None, world: World | None = None,
             settings: SimSettings | None = None,
             progress: Callable[[float], None] | None = None,
             initial_state: FloatArray | None = None,
             model: VehicleParams | None = None,
             controller: Controller | None = None) -> Flight:
    """Fly ``trajectory`` from a hover at its start through a controller and the dynamics.

    Args:
        trajectory: the reference: a :class:`~quadnav.trajectory.model.Trajectory` or
            any other :class:`~quadnav.trajectory.references.contract.Reference`.
        params: the vehicle that flies, the plant (default: the ``tello`` preset).
        gains: the cascade's gains, when no ``controller`` is given (default: those tuned
            for ``model``, the vehicle the controller knows,
            :func:`~quadnav.control.registry.controller_gains`).
        world: the real (uninflated) map: its blocks are obstacles, its boundary the box
            the centre must stay in (within ``settings.boundary_tolerance``) and its lower
            face the floor, met safely only where the reference is on it (within
            ``settings.goal_tolerance``) and no faster than ``settings.touchdown_speed``.
            ``None``: open space, no floor.
        settings: rates, stopping and success rules, disturbances.
        progress: called with the fraction of the flight done, after each chunk of
            :data:`CHUNK_SECONDS` (without it the loop runs the flight in one call).
        initial_state: (17,) state to start from instead of the hover at the start (see
            :mod:`quadnav.vehicle.dynamics`), e.g. to fly a step response.
        model: the vehicle as the controller knows it (default: ``params``); a plant
            that differs from it (heavier, weaker rotors, more drag) is flown by a
            controller tuned for ``model`` that does not know the difference.
        controller: any :class:`~quadnav.control.contract.Controller` (default: the
            cascade with ``gains``, :func:`~quadnav.control.registry.make_controller`).
    """
    params = params or load_params()
    controller = controller or make_controller(DEFAULT_CONTROLLER, model or params, gains)
    settings = settings or SimSettings()
    began = time.perf_counter()
    dt = 1.0 / settings.control_rate
    steps = flight_steps(trajectory.duration, settings)
    references = reference_table(trajectory, dt, steps)
    forces, noise = _disturbances(settings, steps, dt)
    vehicle = vehicle_arrays(params)
    controller_model = vehicle if model is None else vehicle_arrays(model)
    state = (hover_state(params, references[0, REFERENCE_POSITION], references[0, REFERENCE_YAW])
             if initial_state is None
             else np.array(initial_state, dtype=np.float64).reshape(STATE_SIZE))
    memory = controller.new_memory()
    where = loop.scene(world, vehicle.half_size, settings.boundary_tolerance,
                       touchdown=(settings.touchdown_speed, settings.goal_tolerance))
    acting = loop.Disturbances(forces, np.zeros((steps, 3)), noise, settings.noisy)
    every = settings.record_every
    record = loop.new_record(steps, every)
    chunk = steps if progress is None else max(1, round(CHUNK_SECONDS / dt))

    def run(first: int, last: int) -> tuple[int, int]:
        return loop.run_steps(controller, state, memory, first, last, references, vehicle,
                              controller_model, settings.substeps, dt, where, acting, record)

    run(0, 0)  # no step: loads the compiled loop, the one-off cost timed apart
    if controller.python is not None or settings.wind_model is not None:
        run = python_steps(run, controller, settings, trajectory, state, memory, references,
                           acting)
    loaded = time.perf_counter()
    done, code = 0, loop.RUNNING
    while done < steps and code == loop.RUNNING:
        code, ran = run(done, min(done + chunk, steps))
        done += ran
        if progress is not None:
            progress(done / steps)
    flown = time.perf_counter()
    kept = (done - 1) // every + 1
    t = np.append(np.arange(kept) * every * dt, done * dt)
    ending = _ENDINGS.get(code, Ending.COMPLETED)
    count = max(record.stats[loop.STEPS], 1.0)
    states = np.vstack([record.states[:kept], state])
    return Flight(
        t=t, states=states,
        commands=np.vstack([record.commands[:kept], record.commands[kept - 1]]),
        reference=np.vstack([references[::every][:kept], references[min(done, steps - 1)]]),
        goal=np.array(trajectory.position(trajectory.duration)), ending=ending,
        contact_time=None if ending is Ending.COMPLETED else done * dt,
        contact_block=(int(record.stats[loop.CONTACT_BLOCK]) if ending is Ending.COLLISION
                       else None),
        rms_tracking_error=float(np.sqrt(record.stats[loop.SUM_SQUARED_ERROR] / count)),
        max_tracking_error=float(record.stats[loop.MAX_ERROR]),
        max_velocity_error=float(record.stats[loop.MAX_VELOCITY_ERROR]),
        mixer_saturation=float(record.stats[loop.SATURATED] / count),
        wall_time=flown - loaded,
        load_time=loaded - began,
        rotor_energy=rotor_energy(t, states, params),
        floor_speed=(None if record.stats[loop.FLOOR_SPEED] < 0
                     else float(record.stats[loop.FLOOR_SPEED])),
        body_outside=(Excursion() if world is None else body_excursion(
            t, states[:, POSITION], states[:, ATTITUDE], vehicle.half_size, world.boundary)),
        info={"vehicle": params.name, "physics_rate_hz": settings.physics_rate,
              "control_rate_hz": settings.control_rate, "seed": settings.seed})


def python_steps(run: Callable[[int, int], tuple[int, int]], controller: Controller,
                 settings: SimSettings, trajectory: Reference, state: FloatArray,
                 memory: FloatArray, references: FloatArray, acting: loop.Disturbances
                 ) -> Callable[[int, int], tuple[int, int]]:
    """``run(first, last)`` (control steps ``first..last - 1`` of the compiled loop) as one
    call per control step, each after the Python parts: the wind model's velocity at the
    vehicle's position, written into ``acting.wind``, and the controller's Python side,
    which sets its ``memory`` (see the module docstring). Seeds numpy's and Python's global
    random generators with ``settings.seed`` and builds the wind model afresh."""
    np.random.seed(settings.seed)
    random.seed(settings.seed)
    wind = None if settings.wind_model is None else load_wind(settings.wind_model)
    python = controller.python
    dt = 1.0 / settings.control_rate
    jerk_snap = (None if python is None
                 else jerk_snap_table(trajectory, dt, len(references), references))

    def run_each(first: int, last: int) -> tuple[int, int]:
        for k in range(first, last):
            t = k * dt
            if wind is not None:
                acting.wind[k] = wind.at(t, state[POSITION])
            if python is not None and jerk_snap is not None:
                seen = loop.measured(state, acting.noise[k]) if acting.noisy else state
                python.before_step(memory, t, seen, references[k], jerk_snap[k],
                                   acting.wind[k])
            code, ran = run(k, k + 1)
            if code != loop.RUNNING:
                return code, k - first + ran
        return loop.RUNNING, last - first

    return run_each


def rotor_energy(t: FloatArray, states: FloatArray, params: VehicleParams) -> float:
    """The rotors' aerodynamic work, J, over states (N, 17) at times (N,) s: ``k_m w^3``
    summed over the rotors and integrated by trapezoids (see :class:`Flight`)."""
    power = params.torque_coefficient * np.sum(states[:, ROTORS] ** 3, axis=1)
    return float(np.sum(0.5 * (power[1:] + power[:-1]) * np.diff(t)))
