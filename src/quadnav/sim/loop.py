"""The closed loop, compiled with numba: sensors -> controller -> RK4 physics -> checks.

:func:`fly_steps` runs control steps ``first..last`` in place on the state and the
controller memory, so a driver can run a flight in chunks (for a progress bar) at no
cost. Each control step: add the measurement noise; run the controller's step (any
:class:`~quadnav.control.contract.Controller`, passed in as a compiled function);
accumulate the tracking error; record every ``record_every``-th step; then ``substeps``
RK4 steps, each followed by the stop checks (non-finite or upside-down state, centre
outside the boundary, body box touching a real block, the floor met where the reference
is not on it, or too fast: :func:`touchdown`). :func:`run_steps` is how Python calls it for a
controller.
"""

from __future__ import annotations

import math
import threading
import weakref
from typing import Any, NamedTuple

import numba
import numpy as np
from numba import njit
from numba.core.types import CompileResultWAP

from quadnav.control.contract import REFERENCE_VELOCITY, Controller
from quadnav.control.contract import SATURATED as STEP_SATURATED
from quadnav.sim.collision import body_grid, touched_block
from quadnav.vehicle import quaternion
from quadnav.vehicle.dynamics import (
    ATTITUDE,
    POSITION,
    RATES,
    STATE_SIZE,
    VELOCITY,
    VehicleArrays,
    rk4_step,
    rk4_workspace,
)
from quadnav.world.blockgrid import GridArrays
from quadnav.world.model import World

#: Stop codes returned by :func:`fly_steps` (see :class:`~quadnav.sim.flight.Ending`).
RUNNING, COLLISION, LEFT_BOUNDARY, DIVERGED, FLOOR = 0, 1, 2, 3, 4
#: Layout of the statistics array (:data:`STATS_SIZE`,): ``FLOOR_SPEED`` is the fastest the
#: centre met the floor, m/s (-1: never).
(SUM_SQUARED_ERROR, MAX_ERROR, MAX_VELOCITY_ERROR, STEPS, SATURATED, CONTACT_BLOCK,
 FLOOR_SPEED) = range(7)
STATS_SIZE = 7


class Scene(NamedTuple):
    """Where the vehicle flies, as compiled code takes it (:func:`scene`)."""

    boundary: np.ndarray  # (6,) the box the centre must stay in, m
    blocks: np.ndarray  # (N, 6) real blocks, m
    grid: GridArrays  # :func:`~quadnav.sim.collision.body_grid` of the blocks
    floor_z: float  # height of the floor, m (-inf: none)
    touchdown_speed: float  # fastest the floor may be met, m/s (inf: any speed)
    touchdown_height: float  # highest the reference may then be above it, m (inf: any)


class Disturbances(NamedTuple):
    """What acts on the flight besides the controller, per control step."""

    forces: np.ndarray  # (K, 3) external force, N
    wind: np.ndarray  # (K, 3) the wind's velocity, m/s: the drag acts on the airspeed
    noise: np.ndarray  # (K, 12) measurement noise (see measured)
    noisy: bool  # whether to add the noise (skipped when all zero)


class Record(NamedTuple):
    """Where the loop writes what happened."""

    every: int  # control steps per recorded row
    states: np.ndarray  # (R, 17): row k // every written at control steps k divisible by every
    commands: np.ndarray  # (R, 4) motor commands, likewise
    stats: np.ndarray  # (STATS_SIZE,) running tracking statistics


def scene(world: World | None, half_size: np.ndarray, tolerance: float = 0.0,
          floor_z: float | None = None, touchdown: tuple[float, float] = (np.inf, np.inf)
          ) -> Scene:
    """The scene of ``world`` for a body of half sizes ``half_size`` (3,) m: its boundary
    widened by ``tolerance`` m, its blocks and their grid, its floor (its lower face, or
    ``floor_z``), and how the floor may be met: ``touchdown`` (fastest m/s, highest the
    reference may then be above the floor m; by default at any speed anywhere, see
    :func:`touchdown`). ``None``: open space without blocks, with no floor unless
    ``floor_z``."""
    speed, height = (float(value) for value in touchdown)
    if world is None:
        grid = body_grid(World(np.array([-1.0, -1, -1, 1, 1, 1])), half_size)
        return Scene(np.array([-np.inf] * 3 + [np.inf] * 3), np.zeros((0, 6)), grid,
                     -np.inf if floor_z is None else float(floor_z), speed, height)
    boundary = world.boundary + np.repeat([-1.0, 1.0], 3) * tolerance
    return Scene(boundary, np.array(world.blocks), body_grid(world, half_size),
                 float(world.lower[2]) if floor_z is None else float(floor_z), speed, height)


def still_air(steps: int) -> Disturbances:
    """No force, no wind and no sensor noise over ``steps`` control steps."""
    return Disturbances(np.zeros((steps, 3)), np.zeros((steps, 3)), np.zeros((steps, 12)),
                        False)


def new_record(steps: int, every: int = 1) -> Record:
    """Empty records for ``steps`` control steps, a row every ``every``."""
    rows = (steps + every - 1) // every
    stats = np.zeros(STATS_SIZE)
    stats[CONTACT_BLOCK] = -1
    stats[FLOOR_SPEED] = -1
    return Record(every, np.zeros((rows, STATE_SIZE)), np.zeros((rows, 4)), stats)


@njit(cache=True)
def measured(state: np.ndarray, noise: np.ndarray) -> np.ndarray:
    """The state as the sensors see it: noise (12,) on position, velocity, attitude
    (a small rotation) and body rates."""
    out = state.copy()
    attitude = quaternion.multiply(state[ATTITUDE],
                                   quaternion.from_rotation_vector(noise[6:9]))
    for i in range(6):  # element by element: array copies compile error messages
        out[i] += noise[i]  # position and velocity
    for i in range(4):
        out[ATTITUDE.start + i] = attitude[i]
    for i in range(3):
        out[RATES.start + i] += noise[9 + i]
    return out


@njit(cache=True)
def _stop_code(state, v: VehicleArrays, where: Scene, stats) -> int:
    for value in state:
        if not math.isfinite(value):
            return DIVERGED
    r = quaternion.to_matrix(state[ATTITUDE])
    if r[2, 2] < 0.0:
        return DIVERGED
    for a in range(3):
        if not where.boundary[a] <= state[a] <= where.boundary[a + 3]:
            return LEFT_BOUNDARY
    block = touched_block(state[POSITION], r, v.half_size, where.blocks, where.grid)
    if block >= 0:
        stats[CONTACT_BLOCK] = block
        return COLLISION
    return RUNNING


@njit(cache=True)
def touchdown(speed: float, reference, where: Scene, stats) -> int:
    """The floor met at ``speed`` m/s while tracking ``reference`` (11,): a landing (or the
    rest before a take-off), RUNNING, when the reference is then on the floor (at most
    ``where.touchdown_height`` above it) and the floor is met no faster than
    ``where.touchdown_speed``; else a crash, FLOOR. Keeps the fastest in ``stats``."""
    stats[FLOOR_SPEED] = max(stats[FLOOR_SPEED], speed)
    if speed > where.touchdown_speed or reference[2] - where.floor_z > where.touchdown_height:
        return FLOOR
    return RUNNING


@njit(cache=True)
def fly_steps(step, state: np.ndarray, memory: np.ndarray, first: int, last: int,
              references: np.ndarray, v: VehicleArrays, model: VehicleArrays, g,
              substeps: int, dt_control: float, where: Scene, acting: Disturbances,
              record: Record) -> tuple[int, int]:
    """Run control steps ``first..last - 1``; returns (stop code, steps done).

    Args:
        step: the controller's compiled step (see :mod:`quadnav.control.contract`).
        state: (17,) vehicle state, updated in place.
        memory: controller memory, updated in place.
        first: first control step to run (its index into the per-step tables).
        last: one past the last control step to run.
        references: (K, 11) reference per control step (the last row is held after).
        v: the vehicle that flies, the plant (:func:`~quadnav.vehicle.dynamics.vehicle_arrays`):
            its dynamics are integrated and its body box checked for contact.
        model: the vehicle as the controller knows it (``v`` itself unless the plant
            differs from the model, e.g. a heavier vehicle than the controller assumes).
        g: the controller's compiled gains.
        substeps: RK4 steps per control step.
        dt_control: control period, s.
        where: the boundary, blocks and floor, and where the floor may be met
            (:func:`scene`).
        acting: forces, wind and sensor noise per control step.
        record: where the states, commands and statistics go (:func:`new_record`).
    """
    dt = dt_control / substeps
    work = rk4_workspace()
    last_reference = references.shape[0] - 1
    for k in range(first, last):
        reference = references[min(k, last_reference)]
        seen = measured(state, acting.noise[k]) if acting.noisy else state
        commands = step(memory, seen, reference, g, model, dt_control)
        error = 0.0
        velocity_error = 0.0
        for a in range(3):
            error += (state[a] - reference[a]) ** 2
            velocity_error += (state[VELOCITY.start + a]
                               - reference[REFERENCE_VELOCITY.start + a]) ** 2
        stats = record.stats
        stats[SUM_SQUARED_ERROR] += error
        stats[MAX_ERROR] = max(stats[MAX_ERROR], math.sqrt(error))
        stats[MAX_VELOCITY_ERROR] = max(stats[MAX_VELOCITY_ERROR], math.sqrt(velocity_error))
        stats[STEPS] += 1.0
        stats[SATURATED] += memory[STEP_SATURATED]
        if k % record.every == 0:
            row = k // record.every
            for i in range(len(state)):
                record.states[row, i] = state[i]
            for i in range(len(commands)):
                record.commands[row, i] = commands[i]
        for _ in range(substeps):
            speed = rk4_step(state, commands, v, acting.forces[k], acting.wind[k], dt,
                             where.floor_z, work)
            code = _stop_code(state, v, where, stats)
            if code == RUNNING and speed >= 0.0:
                code = touchdown(speed, reference, where, stats)
            if code != RUNNING:
                return code, k + 1 - first
    return RUNNING, last - first


_compiling = threading.Lock()
#: The compiled step of each controller whose loop this process has loaded, as numba takes
#: a first-class function at the least cost: its compiled wrapper's address, found once
#: (passing the step's dispatcher makes numba look it up on every call; the emulator calls
#: run_steps every 10 ms and a plain-Python controller once per control step).
_loaded: weakref.WeakKeyDictionary[Controller, CompileResultWAP] = weakref.WeakKeyDictionary()


def run_steps(controller: Controller, *args: Any) -> tuple[int, int]:
    """:func:`fly_steps` with ``controller``'s step and gains: ``args`` are the arguments
    after ``step`` with the gains left out, from ``state`` to ``record`` in order.

    The loop is compiled once per type of gains and kept in numba's cache on disk (the
    step is passed as a first-class function, so a new controller does not recompile
    it); then compiling stays off, so a call never compiles a loop for one step alone.
    The first call with a controller loads its loop and its step; later ones go straight
    to them.
    """
    args = (*args[:7], controller.gains, *args[7:])
    step = _loaded.get(controller)
    if step is not None:
        try:
            return fly_steps(step, *args)
        except TypeError:  # other argument types than its loop was loaded for
            pass
    function_type = controller.function_type(args[6])
    signature = (function_type, *(numba.typeof(a) for a in args))
    with _compiling:  # the emulator's thread and the caller's may both get here
        if signature not in fly_steps.overloads:
            fly_steps.disable_compile(False)
            try:
                fly_steps.compile(signature)
            finally:
                fly_steps.disable_compile(True)
        step = CompileResultWAP(controller.compiled_step(args[6]))
    _loaded[controller] = step
    return fly_steps(step, *args)
