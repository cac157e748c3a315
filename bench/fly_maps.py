"""Flights at the asked speed: every course map with a path and every built-in world, at 1, 2
and 3 m/s with a 3 m/s^2 limit, over several seeds (planner and simulation alike).

Run: ``python bench/fly_maps.py [--seeds 10] [--workers 2]``, or ``--quick`` for a smoke
run (2 seeds, two maps). Each flight is ``quadnav fly``'s mission (``fly_mission``, default
planner budget, minimum snap with the ``fastest`` timing, the Tello, its gains). Printed
per speed: flights that reached the goal without contact, contacts, the largest RMS
tracking error, the median and largest ratio of the trajectory's duration to the
rest-to-rest bound along its own curve (``L / v + v / a``), the median mean speed, the
least margin kept by the trajectory (measured exactly) and by the flight, and the maps
where a flight failed. Nothing is asserted; wall times are not measured.
"""

from __future__ import annotations

import argparse
import multiprocessing
import statistics
import warnings
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np
from trajectory import ACCELERATION, SAMPLES, SPEEDS, peaks, queries

from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.mission import MissionSettings, fly_mission
from quadnav.sim.settings import SimSettings
from quadnav.trajectory.generate import TrajectorySettings
from quadnav.trajectory.timing.segment_times import rest_to_rest_duration


@dataclass(frozen=True)
class Outcome:
    """One flight of map ``name`` at ``v`` m/s with ``seed``; ``error``: a refusal."""

    name: str
    v: float
    seed: int
    success: bool = False
    contact: bool = False
    rms: float = float("nan")
    ratio: float = float("nan")
    mean_speed: float = float("nan")
    trajectory_margin: float = float("nan")
    flight_margin: float = float("nan")
    error: str = ""


def fly(query: tuple, v: float, seed: int) -> Outcome:
    """Fly ``query`` at ``v`` m/s with ``seed``."""
    name, world, start, goal, margin = query
    base = MissionSettings()
    settings = MissionSettings(planning=base.planning.replace(seed=seed),
                               trajectory=TrajectorySettings(v_max=v, a_max=ACCELERATION),
                               sim=SimSettings(seed=seed))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PlanningWarning)
            mission = fly_mission(world, start, goal, margin, settings)
    except QuadnavError as error:
        return Outcome(name, v, seed, error=str(error))
    if mission.trajectory is None:
        return Outcome(name, v, seed, error="no path")
    metrics = mission.metrics()
    trajectory = mission.trajectory
    t = np.linspace(0.0, trajectory.duration, SAMPLES)
    length, _, _ = peaks(t, trajectory.velocity(t), trajectory.acceleration(t))
    return Outcome(name, v, seed, mission.success, bool(metrics["collision"]),
                   mission.flight.rms_tracking_error,
                   trajectory.duration / float(rest_to_rest_duration(length, v, ACCELERATION)),
                   length / trajectory.duration, metrics["trajectory_margin_m"] / margin,
                   metrics["flight_margin_m"] / margin)


def _fly_job(job: tuple) -> Outcome:
    return fly(*job)


def summary(outcomes: list[Outcome]) -> None:
    """Print one line per speed."""
    for v in SPEEDS:
        rows = [o for o in outcomes if o.v == v]
        flown = [o for o in rows if not o.error]
        good = sum(o.success for o in rows)
        slowest = max(flown, key=lambda o: o.ratio)
        failed = sorted({f"{o.name} (seed {o.seed}{': ' + o.error if o.error else ''})"
                         for o in rows if not o.success})
        print(f"{v:g} m/s: {good}/{len(rows)} reached the goal cleanly, "
              f"{sum(o.contact for o in rows)} contacts; RMS tracking error max "
              f"{100 * max(o.rms for o in flown):.2f} cm; duration / bound median "
              f"{statistics.median(o.ratio for o in flown):.3f}, max "
              f"{slowest.ratio:.3f} ({slowest.name}, seed {slowest.seed}); mean speed median "
              f"{statistics.median(o.mean_speed for o in flown):.2f} m/s; margin kept (share "
              f"of the asked) trajectory min {min(o.trajectory_margin for o in flown):.3f}, "
              f"flight min {min(o.flight_margin for o in flown):.3f}")
        for line in failed:
            print(f"  failed: {line}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    seeds = 2 if args.quick else args.seeds
    jobs = [(query, v, seed) for query in queries(args.quick) for v in SPEEDS
            for seed in range(seeds)]
    print(f"{len(jobs)} flights: {len(jobs) // (len(SPEEDS) * seeds)} maps x "
          f"{len(SPEEDS)} speeds x {seeds} seeds, {ACCELERATION:g} m/s^2")
    spawn = multiprocessing.get_context("spawn")  # numba's OpenMP forbids fork
    with ProcessPoolExecutor(args.workers, mp_context=spawn) as pool:
        outcomes = list(pool.map(_fly_job, jobs, chunksize=4))
    summary(outcomes)


if __name__ == "__main__":
    main()
