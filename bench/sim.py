"""Benchmark: the closed-loop flight simulation — quadnav's compiled loop against a
rotorpy-style loop, and the whole ``quadnav fly`` command, cold and warm.

Run: ``python bench/sim.py [--repeats 7] [--baseline-repeats 3] [--fly-repeats 3]``, or
``python bench/sim.py --quick`` for a smoke run (3, 1 and 1 repeats, a 5 s baseline flight).

The flight: a minimum-snap trajectory (``make_trajectory``, ``v_max`` 2 m/s, checked
against the inflated map) through fixed waypoints across the built-in ``forest`` — the
corners of a refined RRT* path from its start to its goal, about 26 s long — flown by
the default vehicle (``tello``) and gains, plus the 2 s settling time. Numba runs on one
thread in this process (the ``quadnav fly`` runs keep their defaults). It prints:

* quadnav: :func:`quadnav.sim.simulate.simulate` at 1 kHz physics (RK4) and 1 kHz
  control, with its collision, boundary and divergence checks at every physics step: the
  real-time factor (simulated seconds / wall seconds of the whole call), median over
  repeated runs after a warm-up run (numba compilation or cache loading) that is not
  counted. Target: at least 500x.
* the baseline, measured in the same run on the same trajectory, vehicle and controller:
  the loop of rotorpy — the controller (here the compiled
  :func:`quadnav.control.cascade.control`) at 100 Hz, and after each control step the
  physics integrated over the step by ``scipy.integrate.solve_ivp`` (RK45, its default
  tolerances, as rotorpy) on a numpy derivative of quadnav's 17-state model
  (:func:`numpy_derivative`, checked against the compiled one), then the quaternion
  renormalised. Like rotorpy, it does no collision checks in the loop. Printed: its
  real-time factor and quadnav's ratio over it (the issue quotes rotorpy at about 2.4x
  real time at 100 Hz on this kind of machine); also both flights' RMS tracking errors,
  to show the baseline flies the same flight.
* ``quadnav fly -o DIR --quiet`` on the default world as a subprocess, whole-process wall
  time: cold — the first run with ``NUMBA_CACHE_DIR`` set to a new, empty directory, so
  every compiled function is compiled and written there — and warm: the median of the
  next runs, reusing that directory. Also printed: the exit codes (1: the flight failed,
  e.g. no path within the planner's time budget) and the number of numba index files the
  cold run wrote there, showing numba honoured the variable for the installed package.

Nothing is asserted.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np
from scipy.integrate import solve_ivp

from quadnav.control.cascade import control, gain_arrays, new_memory
from quadnav.control.contract import REFERENCE_POSITION, REFERENCE_YAW
from quadnav.control.gains import Gains
from quadnav.sim.settings import SimSettings
from quadnav.sim.simulate import reference_table, simulate
from quadnav.trajectory import SafeSpace, Trajectory, TrajectorySettings, make_trajectory
from quadnav.vehicle.dynamics import (
    ATTITUDE,
    POSITION,
    RATES,
    ROTORS,
    STATE_SIZE,
    VELOCITY,
    VehicleArrays,
    derivative,
    hover_state,
    vehicle_arrays,
)
from quadnav.vehicle.params import VehicleParams, load_params
from quadnav.world import load_world
from quadnav.world.model import World

#: Waypoints across the built-in forest, m: the corners of a refined RRT* path (seed 0)
#: from its start (1, 1, 1) to its goal (19, 19, 3).
WAYPOINTS = np.array([[1.0, 1.0, 1.0], [10.3, 9.85, 2.17], [11.65, 11.19, 2.32],
                      [12.16, 11.72, 2.37], [19.0, 19.0, 3.0]])
#: Speed limit of the trajectory, m/s.
V_MAX = 2.0
#: Control rate of the rotorpy-style baseline, Hz.
BASELINE_RATE = 100.0
#: Target real-time factor of quadnav's loop.
TARGET = 500.0


# ------------------------------------------------------------------- the flight
def forest_flight() -> tuple[World, Trajectory]:
    """The forest and the benchmark trajectory through :data:`WAYPOINTS`."""
    world = load_world("forest")
    return world, make_trajectory(WAYPOINTS, TrajectorySettings(v_max=V_MAX),
                                  SafeSpace(world, world.margin))


def quadnav_run(trajectory: Trajectory, world: World) -> tuple[float, float, float]:
    """(wall s, simulated s, RMS tracking error m) of one call of ``simulate``."""
    began = time.perf_counter()
    flight = simulate(trajectory, world=world, settings=SimSettings())
    wall = time.perf_counter() - began
    return wall, float(flight.t[-1]), flight.rms_tracking_error


# ------------------------------------------------------------------- the baseline
def numpy_derivative(x: np.ndarray, rotor_target: np.ndarray, v: VehicleArrays,
                     force: np.ndarray, wind: np.ndarray) -> np.ndarray:
    """d state / dt (17,) of :func:`quadnav.vehicle.dynamics.derivative`, in numpy: state
    ``x`` (17,), rotor speed targets (4,) rad/s, external force (3,) N, wind velocity (3,)
    m/s."""
    qw, qx, qy, qz = x[ATTITUDE]
    w = x[RATES]
    rotors = x[ROTORS]
    R = np.array([
        [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)],
        [2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)],
        [2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)],
    ])
    squared = rotors * rotors
    thrusts = v.thrust_coefficient * squared
    torque = np.array([v.allocation[1] @ thrusts, v.allocation[2] @ thrusts,
                       -v.torque_coefficient * (v.spin @ squared)])
    drag = R @ (v.drag * (R.T @ (x[VELOCITY] - wind)))
    acceleration = (R[:, 2] * thrusts.sum() - drag + force) / v.mass
    acceleration[2] -= v.gravity
    G = np.array([[-qx, -qy, -qz], [qw, -qz, qy], [qz, qw, -qx], [-qy, qx, qw]])
    spin_momentum = v.inertia * w
    out = np.empty(STATE_SIZE)
    out[POSITION] = x[VELOCITY]
    out[VELOCITY] = acceleration
    out[ATTITUDE] = 0.5 * G @ w
    out[RATES] = (torque - np.cross(w, spin_momentum)) / v.inertia
    out[ROTORS] = (rotor_target - rotors) / v.motor_time_constant
    return out


def derivative_mismatch(params: VehicleParams, samples: int = 100) -> float:
    """Largest |numpy - compiled| derivative component over random states (relative to
    the largest component), the check that the baseline integrates the same model."""
    rng = np.random.default_rng(0)
    v = vehicle_arrays(params)
    worst, out = 0.0, np.empty(STATE_SIZE)
    for _ in range(samples):
        x = rng.normal(size=STATE_SIZE)
        x[ATTITUDE] /= np.linalg.norm(x[ATTITUDE])
        x[ROTORS] = rng.uniform(0.0, params.rotor_speed_max, 4)
        target = rng.uniform(0.0, params.rotor_speed_max, 4)
        force, wind = rng.normal(size=3), rng.normal(size=3)
        derivative(x, target, v, force, wind, out)
        expected = numpy_derivative(x, target, v, force, wind)
        worst = max(worst, float(np.max(np.abs(out - expected)) / np.max(np.abs(out))))
    return worst


def baseline_run(trajectory: Trajectory, params: VehicleParams, gains: Gains,
                 settle_time: float, horizon: float | None) -> tuple[float, float, float]:
    """(wall s, simulated s, RMS tracking error m) of the rotorpy-style loop: control at
    :data:`BASELINE_RATE`, then ``solve_ivp`` over the control step. ``horizon``: fly only
    that many seconds (default: the trajectory and ``settle_time``)."""
    began = time.perf_counter()
    dt = 1.0 / BASELINE_RATE
    total = trajectory.duration + settle_time if horizon is None else horizon
    steps = int(np.ceil(total / dt - 1e-9))
    references = reference_table(trajectory, dt, steps)
    v = vehicle_arrays(params)
    g = gain_arrays(gains)
    memory = new_memory()
    state = hover_state(params, references[0, REFERENCE_POSITION], references[0, REFERENCE_YAW])
    still = np.zeros(3)
    squared_error = 0.0
    for reference in references:
        squared_error += float(np.sum((state[POSITION] - reference[REFERENCE_POSITION]) ** 2))
        commands = control(memory, state, reference, g, v, dt)
        target = v.rotor_speed_max * np.sqrt(np.clip(commands, 0.0, 1.0))
        solution = solve_ivp(lambda _t, s, target=target: numpy_derivative(s, target, v,
                                                                          still, still),
                             (0.0, dt), state)
        state = solution.y[:, -1].copy()
        state[ATTITUDE] /= np.linalg.norm(state[ATTITUDE])
    wall = time.perf_counter() - began
    return wall, steps * dt, float(np.sqrt(squared_error / steps))


# ------------------------------------------------------------------- quadnav fly
def fly_once(cache: Path, output: Path) -> tuple[float, int]:
    """(whole-process wall time s, exit code) of ``quadnav fly -o output --quiet`` with
    numba's cache in ``cache``; a failing run's message goes to stderr."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    command = [sys.executable, "-m", "quadnav", "fly", "-o", str(output), "--quiet"]
    began = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - began
    if done.returncode != 0:
        print(f"  quadnav fly exited {done.returncode}: {done.stderr.strip()}",
              file=sys.stderr, flush=True)
    return wall, done.returncode


def fly_times(warm_runs: int) -> tuple[tuple[float, int], list[tuple[float, int]], int]:
    """The cold run and the warm runs, each (wall s, exit code), and the number of numba
    index files in the cache after the cold run."""
    with tempfile.TemporaryDirectory(prefix="quadnav-bench-") as folder:
        root = Path(folder)
        cache = root / "numba-cache"
        cache.mkdir()
        cold = fly_once(cache, root / "out-cold")
        index_files = len(list(cache.rglob("*.nbi")))
        warm = [fly_once(cache, root / f"out-{i}") for i in range(warm_runs)]
    return cold, warm, index_files


# ------------------------------------------------------------------- driver
@dataclass(frozen=True)
class Runs:
    """Per-run (wall s, simulated s, RMS tracking error m) of one loop."""

    runs: list[tuple[float, float, float]]

    @property
    def factor(self) -> float:
        """Median real-time factor, simulated s / wall s."""
        return statistics.median(sim / wall for wall, sim, _ in self.runs)

    @property
    def wall(self) -> float:
        """Median wall time, s."""
        return statistics.median(wall for wall, _, _ in self.runs)

    @property
    def simulated(self) -> float:
        """Simulated time of a run, s."""
        return self.runs[0][1]

    @property
    def rms(self) -> float:
        """RMS tracking error of the last run, m."""
        return self.runs[-1][2]


def repeat(run: Callable[[], tuple[float, float, float]], repeats: int) -> Runs:
    """``repeats`` calls of ``run``."""
    return Runs([run() for _ in range(repeats)])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=None,
                        help="timed runs of quadnav's loop (7; quick 3)")
    parser.add_argument("--baseline-repeats", type=int, default=None,
                        help="timed runs of the baseline loop (3; quick 1)")
    parser.add_argument("--fly-repeats", type=int, default=None,
                        help="warm runs of quadnav fly (3; quick 1)")
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: 3, 1 and 1 runs, the baseline flies 5 s")
    args = parser.parse_args()
    repeats = args.repeats or (3 if args.quick else 7)
    baseline_repeats = args.baseline_repeats or (1 if args.quick else 3)
    fly_repeats = args.fly_repeats or (1 if args.quick else 3)
    horizon = 5.0 if args.quick else None
    numba.set_num_threads(1)

    world, trajectory = forest_flight()
    params, gains, settings = load_params(), Gains(), SimSettings()
    print("  quadnav loop: warm-up, then timing", file=sys.stderr, flush=True)
    quadnav_run(trajectory, world)
    ours = repeat(lambda: quadnav_run(trajectory, world), repeats)
    print("  baseline loop", file=sys.stderr, flush=True)
    mismatch = derivative_mismatch(params)
    base = repeat(lambda: baseline_run(trajectory, params, gains, settings.settle_time,
                                       horizon), baseline_repeats)
    print("  quadnav fly: cold, then warm", file=sys.stderr, flush=True)
    cold, warm, index_files = fly_times(fly_repeats)

    print(f"flight: forest, minimum snap through {len(WAYPOINTS)} waypoints, v_max {V_MAX:g} "
          f"m/s, {trajectory.duration:.1f} s + {settings.settle_time:g} s settling; vehicle "
          f"{params.name}, default gains; numba threads {numba.get_num_threads()}\n")
    print(f"## Closed loop, real-time factor = simulated s / wall s (median; quadnav "
          f"{repeats} runs after a warm-up, baseline {baseline_repeats})\n")
    rows = [
        ["quadnav simulate (RK4 1 kHz, control 1 kHz, checks)", f"{ours.simulated:.1f}",
         f"{ours.wall * 1e3:.1f} ms", f"{ours.factor:.0f}x (target >= {TARGET:.0f}x)",
         f"{ours.rms * 1e3:.2f}"],
        [f"baseline, rotorpy-style (solve_ivp RK45, control {BASELINE_RATE:.0f} Hz)",
         f"{base.simulated:.1f}", f"{base.wall:.2f} s", f"{base.factor:.1f}x",
         f"{base.rms * 1e3:.2f}"],
    ]
    print(table(["loop", "simulated s", "wall", "real-time factor", "RMS error mm"], rows))
    print(f"\nquadnav / baseline: {ours.factor / base.factor:.0f}x "
          f"(rotorpy itself: about 2.4x real time at 100 Hz, per the issue)")
    print(f"baseline derivative vs compiled: largest relative difference {mismatch:.1e}\n")
    print(f"## quadnav fly (default world), whole process, s ({fly_repeats} warm runs)\n")
    print(table(["cold (empty NUMBA_CACHE_DIR)", "warm (median)", "warm runs",
                 "exit codes (cold; warm)", "numba index files written by the cold run"],
                [[f"{cold[0]:.1f}", f"{statistics.median(w for w, _ in warm):.1f}",
                  ", ".join(f"{w:.1f}" for w, _ in warm),
                  f"{cold[1]}; {', '.join(str(c) for _, c in warm)}", str(index_files)]]))


def table(header: list[str], rows: list[list[str]]) -> str:
    """A markdown table with columns padded to their widest entry."""
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]

    def line(row: list[str]) -> str:
        return "| " + " | ".join(v.ljust(w) for v, w in zip(row, widths, strict=True)) + " |"

    return "\n".join([line(header), line(["-" * w for w in widths]), *map(line, rows)])


if __name__ == "__main__":
    main()
