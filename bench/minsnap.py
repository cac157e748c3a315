"""Benchmark: minimum snap through 50 waypoints — closed form and Clarabel QPs against SLSQP.

Run: ``python bench/minsnap.py [--repeats 11] [--baseline-repeats 3]``, or
``python bench/minsnap.py --quick`` for a smoke run (3 and 1 repeats).

Two sets of 50 waypoints, with segment times of distance / 1 m/s: a seeded random 3D
walk (steps of 1-3 m in random directions), and a refined RRT* plan through the built-in
``forest`` densified to 50 points (its corners kept, points added along its edges).
On each it prints medians over repeated runs of the whole call of:

* :func:`quadnav.trajectory.polynomials.minsnap.minimum_snap` — the closed form (one sparse
  KKT solve);
* :func:`quadnav.trajectory.polynomials.minsnap_qp.minimum_snap_qp` without inequalities (the same
  problem as a Clarabel QP) and with corridors: each segment's bounding box grown by
  0.5 m, 20 samples per segment;
* the baseline, measured in the same run on the same waypoints and times: the course
  reports' formulation — a dense cost matrix, the same equality constraints, solved per
  axis from zero by ``scipy.optimize.minimize(method="SLSQP")``. It uses our
  normalised-time matrices, which are better conditioned than the reports' raw-time
  monomials, so the comparison is of the solvers alone.

Also printed: the speed-ups (target: the closed form and the corridor QP at least 100x
faster than SLSQP), the relative cost difference between SLSQP and the closed form
(target < 1e-6) with whether SLSQP says it converged, and how far the closed form and the
corridor QP leave the corridors at 200 samples per segment. Nothing is asserted.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import OptimizeResult, minimize

from quadnav.planning import PlannerSettings, make_problem, plan
from quadnav.planning.refine import refine
from quadnav.trajectory import Trajectory
from quadnav.trajectory.polynomials import basis
from quadnav.trajectory.polynomials.minsnap import minimum_snap
from quadnav.trajectory.polynomials.minsnap_qp import minimum_snap_qp
from quadnav.world import load_world

#: Waypoints of every case.
WAYPOINTS = 50
#: Cruise speed that sets the segment times, m/s.
SPEED = 1.0
#: Growth of each segment's bounding box into its corridor, m.
CORRIDOR_MARGIN = 0.5
#: Order of the minimised derivative (snap).
SNAP = 4


def random_walk(count: int, seed: int) -> np.ndarray:
    """(count, 3) waypoints of a 3D walk with steps of 1-3 m in uniform random directions."""
    rng = np.random.default_rng(seed)
    direction = rng.normal(size=(count - 1, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    steps = direction * rng.uniform(1.0, 3.0, size=(count - 1, 1))
    return np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])


def densify(path: np.ndarray, count: int) -> np.ndarray:
    """(count, 3) points along ``path`` (M, 3), M <= count: every corner kept, each edge
    cut into pieces in proportion to its length (at least one)."""
    lengths = np.linalg.norm(np.diff(path, axis=0), axis=1)
    pieces = np.ones(len(lengths), dtype=int)
    for _ in range(count - len(path)):
        pieces[np.argmax(lengths / pieces)] += 1
    parts = [path[:1]]
    for start, end, n in zip(path[:-1], path[1:], pieces, strict=True):
        parts.append(start + np.outer(np.arange(1, n + 1) / n, end - start))
    return np.vstack(parts)


def forest_plan(count: int) -> np.ndarray:
    """A refined RRT* path through the built-in forest (seed 0), densified to ``count``."""
    world = load_world("forest")
    problem = make_problem(world, None, None, world.margin)
    result = plan(problem, PlannerSettings(seed=0, max_iterations=20000, time_limit=60))
    return densify(refine(problem, result).path, count)


def grown_boxes(waypoints: np.ndarray, margin: float) -> np.ndarray:
    """(segments, 6) bounding box of each segment grown by ``margin`` m."""
    return np.hstack([np.minimum(waypoints[:-1], waypoints[1:]) - margin,
                      np.maximum(waypoints[:-1], waypoints[1:]) + margin])


def slsqp_minimum_snap(waypoints: np.ndarray, times: np.ndarray, ftol: float, maxiter: int
                       ) -> tuple[float, list[OptimizeResult]]:
    """Baseline: minimum snap by SLSQP per axis, from zero, on the dense cost matrix and the
    same equality constraints. Returns the cost, m^2/s^7, and the three SciPy results."""
    Q = basis.cost_matrix(times, SNAP).toarray()
    A_sparse, b = basis.equality_constraints(waypoints, times, SNAP, continuity=SNAP)
    A = A_sparse.toarray()
    results = []
    for axis in range(3):
        results.append(minimize(
            lambda x: x @ Q @ x, np.zeros(len(Q)), jac=lambda x: 2 * Q @ x, method="SLSQP",
            constraints=[{"type": "eq", "fun": lambda x, axis=axis: A @ x - b[:, axis],
                          "jac": lambda x: A}],
            options={"ftol": ftol, "maxiter": maxiter}))
    coefficients = np.stack([r.x for r in results], axis=1).reshape(len(times), 2 * SNAP, 3)
    return basis.trajectory_cost(coefficients, times, SNAP), results


def corridor_excess(trajectory: Trajectory, boxes: np.ndarray, per_segment: int) -> float:
    """Largest distance, m, by which segment ``i`` leaves ``boxes[i]``, over ``per_segment``
    + 1 evenly spaced samples of each segment (negative: inside with that clearance)."""
    tau = np.linspace(0.0, 1.0, per_segment + 1)
    t = trajectory.breaks[:-1, None] + trajectory.segment_times[:, None] * tau
    positions = trajectory.position(t.ravel()).reshape(len(boxes), per_segment + 1, 3)
    return float(max(np.max(boxes[:, None, :3] - positions),
                     np.max(positions - boxes[:, None, 3:])))


def timed(function: Callable[[], object], repeats: int) -> tuple[float, object]:
    """Median wall time, s, of ``repeats`` calls, and the last call's result."""
    times, result = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


@dataclass(frozen=True)
class Figures:
    """One case's medians, s, costs, m^2/s^7, and corridor excursions, m."""

    label: str
    closed_s: float
    qp_s: float
    corridor_s: float
    slsqp_s: float
    closed_cost: float
    qp_cost: float
    corridor_cost: float
    slsqp_cost: float
    slsqp_runs: list[OptimizeResult]
    corridor_iterations: int
    closed_excess: float
    corridor_excess: float


def measure(label: str, waypoints: np.ndarray, repeats: int, baseline_repeats: int,
            ftol: float, maxiter: int) -> Figures:
    """Time the three methods on one set of waypoints."""
    times = np.linalg.norm(np.diff(waypoints, axis=0), axis=1) / SPEED
    corridors = grown_boxes(waypoints, CORRIDOR_MARGIN)
    runs: dict[str, Callable[[], object]] = {
        "closed": lambda: minimum_snap(waypoints, times),
        "qp": lambda: minimum_snap_qp(waypoints, times),
        "corridor": lambda: minimum_snap_qp(waypoints, times, corridors=corridors),
    }
    for run in runs.values():
        run()  # warm-up: first-call costs of SciPy and Clarabel are not counted
    print(f"  {label}: timing", file=sys.stderr, flush=True)
    seconds, results = {}, {}
    for name, run in runs.items():
        seconds[name], results[name] = timed(run, repeats)
    print(f"  {label}: SLSQP baseline", file=sys.stderr, flush=True)
    slsqp_s, (slsqp_cost, slsqp_runs) = timed(
        lambda: slsqp_minimum_snap(waypoints, times, ftol, maxiter), baseline_repeats)
    closed, corridor = results["closed"], results["corridor"]
    return Figures(label, seconds["closed"], seconds["qp"], seconds["corridor"], slsqp_s,
                   closed.info["cost"], results["qp"].info["cost"], corridor.info["cost"],
                   slsqp_cost, slsqp_runs, corridor.info["iterations"],
                   corridor_excess(closed, corridors, 200),
                   corridor_excess(corridor, corridors, 200))


# ------------------------------------------------------------------- reporting
def table(header: list[str], rows: list[list[str]]) -> str:
    """A markdown table with columns padded to their widest entry."""
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]

    def line(row: list[str]) -> str:
        return "| " + " | ".join(v.ljust(w) for v, w in zip(row, widths, strict=True)) + " |"

    return "\n".join([line(header), line(["-" * w for w in widths]), *map(line, rows)])


def converged(runs: list[OptimizeResult]) -> str:
    """Whether SLSQP says it converged, and its iterations, per axis."""
    flags = "/".join("yes" if r.success else "NO" for r in runs)
    return f"{flags} ({'/'.join(str(r.nit) for r in runs)} it)"


def report(all_figures: list[Figures], repeats: int, baseline_repeats: int, ftol: float,
           maxiter: int) -> str:
    """The figures as two markdown tables."""
    time_rows, cost_rows = [], []
    for f in all_figures:
        time_rows.append([f.label, f"{f.closed_s * 1e3:.3g}", f"{f.qp_s * 1e3:.3g}",
                          f"{f.corridor_s * 1e3:.3g}", f"{f.slsqp_s:.3g}",
                          f"{f.slsqp_s / f.closed_s:.3g}x", f"{f.slsqp_s / f.qp_s:.3g}x",
                          f"{f.slsqp_s / f.corridor_s:.3g}x"])
        cost_rows.append([f.label, f"{f.closed_cost:.6g}",
                          f"{abs(f.slsqp_cost - f.closed_cost) / f.closed_cost:.1e}",
                          converged(f.slsqp_runs),
                          f"{abs(f.qp_cost - f.closed_cost) / f.closed_cost:.1e}",
                          f"{f.corridor_cost:.6g} ({f.corridor_iterations} it)",
                          f"{f.closed_excess:+.3f}", f"{f.corridor_excess:+.4f}"])
    return "\n".join([
        f"## Wall time of the whole call (median; {repeats} runs, SLSQP {baseline_repeats}; "
        f"SLSQP ftol {ftol:g}, maxiter {maxiter}); speed-up = SLSQP / ours",
        "",
        table(["waypoints", "closed form ms", "QP ms", "corridor QP ms", "SLSQP s",
               "vs closed", "vs QP", "vs corridor QP"], time_rows),
        "",
        "## Snap cost, m^2/s^7; rel. diff = |cost - closed-form cost| / closed-form cost; "
        "corridor excursion = largest distance outside a corridor (< 0: inside), m, at 200 "
        "samples per segment",
        "",
        table(["waypoints", "closed form", "SLSQP rel. diff", "SLSQP converged (x/y/z)",
               "QP rel. diff", "corridor QP (iterations)", "closed form excursion",
               "corridor QP excursion"], cost_rows),
    ])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=None,
                        help="runs of the closed form and the QPs (11; quick 3)")
    parser.add_argument("--baseline-repeats", type=int, default=None,
                        help="runs of the SLSQP baseline (3; quick 1)")
    parser.add_argument("--quick", action="store_true", help="smoke run: 3 and 1 runs")
    parser.add_argument("--ftol", type=float, default=1e-10,
                        help="SLSQP ftol (1e-10: about 1e-12 of the cost; 1e-12 is below the "
                             "rounding of a cost of a few hundred and stalls)")
    parser.add_argument("--maxiter", type=int, default=1000, help="SLSQP maxiter (1000)")
    args = parser.parse_args()
    repeats = args.repeats or (3 if args.quick else 11)
    baseline_repeats = args.baseline_repeats or (1 if args.quick else 3)

    cases = {f"random walk, {WAYPOINTS}": random_walk(WAYPOINTS, seed=1),
             f"forest plan, {WAYPOINTS}": forest_plan(WAYPOINTS)}
    all_figures = [measure(label, waypoints, repeats, baseline_repeats, args.ftol, args.maxiter)
                   for label, waypoints in cases.items()]
    print(f"minimum snap, segment times at {SPEED:g} m/s, corridors = segment bounding boxes "
          f"grown by {CORRIDOR_MARGIN:g} m (20 samples per segment)\n")
    print(report(all_figures, repeats, baseline_repeats, args.ftol, args.maxiter))


if __name__ == "__main__":
    main()
