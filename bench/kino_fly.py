"""Benchmark: quadrotor kinodynamic plans flown closed loop, beside ``fly`` on the same worlds.

Run: ``python bench/kino_fly.py [--seeds 10] [--worlds empty forest window maze]``.

For each built-in world and each seed 0..N-1, with each world's own start, goal and 0.2 m
margin:

* **kino** — :func:`~quadnav.kinodynamic.quadrotor.plan_quadrotor` (the defaults, but a
  budget of up to :data:`ITERATIONS` extensions and :data:`TIME_LIMIT` s, as the maze needs
  20,000-55,000), then :func:`~quadnav.kinoflight.fly_kino_plan` (Tello, cascade), as
  ``quadnav kino quadrotor MAP --fly --iterations 100000 --time 60`` does;
* **fly** — :func:`~quadnav.mission.fly_mission` with the same seed at its default 2 m/s
  (the kinodynamic model's speed limit), as ``quadnav fly MAP --seed N`` does.

Prints, per world and pipeline, the successes and the medians (min-max) over the seeds of
the flight time, the rotors' energy, the RMS and largest tracking errors and the margin the
flight kept. Not a timing benchmark: the planning CPU time is printed for scale only.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from quadnav.kinodynamic.pointmass import SampledQuadrotor
from quadnav.kinodynamic.quadrotor import plan_quadrotor
from quadnav.kinodynamic.settings import KinoSettings
from quadnav.kinoflight import fly_kino_plan
from quadnav.mission import MissionSettings, fly_mission
from quadnav.planning.settings import PlannerSettings
from quadnav.world import load_world

ITERATIONS = 100_000
TIME_LIMIT = 60.0
MARGIN = 0.2
COLUMNS = (("flight_time_s", "flight s", 1.0, "{:.1f}"), ("rotor_energy_j", "energy J", 1.0,
                                                           "{:.0f}"),
           ("rms_tracking_error_m", "RMS cm", 100.0, "{:.1f}"),
           ("max_tracking_error_m", "max cm", 100.0, "{:.1f}"),
           ("flight_margin_m", "margin m", 1.0, "{:.3f}"))


def kino_row(world_spec: str, seed: int) -> tuple[dict | None, float]:
    """The metrics of the kinodynamic plan flown closed loop (None without a plan) and the
    planning CPU time, s."""
    world = load_world(world_spec).replace(margin=MARGIN)
    settings = KinoSettings(seed=seed, max_iterations=ITERATIONS, time_limit=TIME_LIMIT)
    began = time.process_time()
    result = plan_quadrotor(world, world.start, world.goal, settings, SampledQuadrotor(),
                            MARGIN)
    cpu = time.process_time() - began
    if not result.solved:
        return None, cpu
    return fly_kino_plan(world, result, SampledQuadrotor(), settings).metrics(), cpu


def fly_row(world_spec: str, seed: int) -> tuple[dict, float]:
    """The metrics of ``fly`` with ``seed`` and the planning CPU time, s."""
    world = load_world(world_spec)
    settings = MissionSettings(planning=PlannerSettings(seed=seed))
    began = time.process_time()
    mission = fly_mission(world, margin=MARGIN, settings=settings)
    return mission.metrics(), time.process_time() - began


def summary(label: str, rows: list[dict | None], cpu: list[float]) -> str:
    """One table line: successes, then each column's median (min-max)."""
    flown = [row for row in rows if row is not None]
    cells = [f"{sum(bool(row['success']) for row in flown)}/{len(rows)}"]
    for key, _, scale, form in COLUMNS:
        values = np.array([row[key] * scale for row in flown if row[key] is not None])
        cells.append(f"{form.format(np.median(values))} ({form.format(values.min())}-"
                     f"{form.format(values.max())})" if len(values) else "-")
    cells.append(f"{np.median(cpu):.2f}")
    return f"| {label} | " + " | ".join(cells) + " |"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--worlds", nargs="+", default=["empty", "forest", "window", "maze"])
    args = parser.parse_args()
    header = ["world, pipeline", "success", *(name for _, name, _, _ in COLUMNS),
              "planning CPU s"]
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for world_spec in args.worlds:
        for label, run in (("kino --fly", kino_row), ("fly", fly_row)):
            rows, cpu = zip(*(run(world_spec, seed) for seed in range(args.seeds)), strict=True)
            print(summary(f"{world_spec}, {label}", list(rows), list(cpu)), flush=True)


if __name__ == "__main__":
    main()
