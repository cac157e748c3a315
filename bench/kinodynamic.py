"""Benchmark: quadnav's kinodynamic RRT against OMPL's control-based RRT, on the same problems.

Run: ``python bench/kinodynamic.py [--seeds 20] [--time-limit 30] [--json FILE]``, or
``python bench/kinodynamic.py --quick`` for a smoke run (3 seeds, 5 s limit).

Problems, each with the defaults of :class:`~quadnav.kinodynamic.KinoSettings` (goal radius
0.5 m, every control held 0.5 s) and of the vehicle models:

* **diffdrive** — the built-in ``forest`` sliced at z = 1 m, from (1, 1) heading pi/4 (the
  forest's own start, at the diagonal's heading) to (19, 19), margin 0 (the robot's 0.2 m
  radius is kept from every trunk);
* **quadrotor** — the built-in ``forest`` from its own start (1, 1, 1), at rest, to its own
  goal (19, 19, 3), margin 0.2 m.

Planners, each stopping when a state lies within the goal radius or the time limit ends
(ours also after :data:`MAX_ITERATIONS` extensions, far more than any run here needs):

* ``ours`` — :func:`~quadnav.kinodynamic.diffdrive.plan_diffdrive` /
  :func:`~quadnav.kinodynamic.quadrotor.plan_quadrotor` as they come: goal-biased
  sampling, the best of 10 sampled controls per extension;
* ``ours k=1`` — the same with one control per extension, as OMPL's RRT extends;
* ``OMPL`` and ``OMPL b=0.5`` — OMPL 2.0.1's ``control::RRT``, goal bias 0.05 (its default)
  and 0.5 (the probability with which ours samples near the goal).

OMPL is given the same problem: the same control limits, every control held for exactly
the same duration (a propagation step of that duration, one step per control), the same
goal region (a goal whose distance is the position's distance from the goal; its samples
are the goal position at rest, or for the robot at a random heading) and, on every
motion, the *same* exact model propagation and the same exact collision check as ours: a
Python state propagator calls :func:`quadnav.kinodynamic.diffdrive.track` (the exact arc,
sampled so chords stay within the planner's chord tolerance) or
:func:`~quadnav.kinodynamic.pointmass.exact_states` and ``exact_positions``, and checks
the chords exactly against the world inflated as our planner inflates it (for the
quadrotor also the speed limit; its floor check is implied by the chord check, since the
inflated boundary's floor is ``margin + tolerance`` up). What the bindings allow decides
the rest:

* ``StatePropagator`` cannot be subclassed (no constructor is bound), but
  ``setStatePropagator`` takes a Python function; a propagation step cannot reject a
  motion, so the function writes NaN into a colliding motion's end and the state validity
  checker rejects non-finite states (OMPL checks every propagated state);
* the directed control sampler cannot be built with more than OMPL's default one control
  per extension (``SimpleDirectedControlSampler`` has no bound constructor), hence
  ``ours k=1`` for a like-for-like extension;
* OMPL samples whole states uniformly in the bounds (the robot: SE(2) over the inflated
  boundary; the quadrotor: position in the inflated boundary, each velocity component
  within the speed limit) and picks the nearest tree state by the state space's metric.

Times are the wall time until the goal region is reached: ours ``time_to_goal``, OMPL's
``solve`` call (its set-up excluded). OMPL calls back into Python for every propagation
(about 50 us each on top of the model and the check), which is part of its time here.
Iterations are extensions tried (OMPL: propagations). Every planner runs once on each
problem before the timed runs, so compilation is not counted; seeds interleave the
planners. Nothing is asserted.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from planning import cell, median, ratio, solved, table

from quadnav.kinodynamic import KinoResult, KinoSettings
from quadnav.kinodynamic import diffdrive as dd
from quadnav.kinodynamic import quadrotor as quad
from quadnav.kinodynamic.pointmass import SampledQuadrotor, exact_positions, exact_states
from quadnav.kinodynamic.world2d import World2D, load_world2d
from quadnav.planning.registry import ompl_available
from quadnav.world import World, load_world

FloatArray = NDArray[np.float64]

#: Seed of the warm-up runs, outside the range of the timed seeds.
WARM_UP_SEED = 10**6
#: Our planners' iteration cap: far above what any run here needs, and small, as
#: ``plan_diffdrive`` allocates its tree for the cap inside its clock (10^7 would add 8 ms).
MAX_ITERATIONS = 100_000
#: Column labels.
OURS, OURS_K1, OMPL, OMPL_BIASED = "ours", "ours k=1", "OMPL", "OMPL b=0.5"
#: OMPL's goal bias per OMPL column: its default, and the probability ours samples near
#: the goal with.
OMPL_GOAL_BIAS = {OMPL: 0.05, OMPL_BIASED: KinoSettings().goal_bias}


@dataclass(frozen=True)
class Problem:
    """One benchmark query.

    Attributes:
        label: name in the tables.
        vehicle: ``"diffdrive"`` or ``"quadrotor"``.
        world: a :class:`World2D` for the robot, a :class:`World` for the quadrotor.
        start: the robot's (x, y, theta) or the quadrotor's (x, y, z), m and rad.
        goal: (x, y) or (x, y, z), m.
        margin: safety margin, m.
    """

    label: str
    vehicle: str
    world: World2D | World
    start: tuple[float, ...]
    goal: tuple[float, ...]
    margin: float


def problems() -> list[Problem]:
    """The two benchmark problems (see the module docstring)."""
    forest = load_world("forest")
    (x0, y0, _), (x1, y1, _) = forest.start, forest.goal
    return [
        Problem("diffdrive, forest at z = 1 m", "diffdrive", load_world2d(forest, 1.0),
                (x0, y0, math.atan2(y1 - y0, x1 - x0)), (x1, y1), 0.0),
        Problem("quadrotor, forest", "quadrotor", forest, tuple(forest.start),
                tuple(forest.goal), 0.2),
    ]


@dataclass(frozen=True)
class Outcome:
    """One run: time to the goal region (s, ``inf`` if not reached), extensions tried,
    tree states, and how long the plan lasts (s of motion, ``inf`` if none)."""

    time_to_goal: float
    iterations: int
    nodes: int
    duration: float

    @property
    def extension_us(self) -> float:
        """Wall time per extension tried until the goal was reached, us (``inf`` if not)."""
        return 1e6 * self.time_to_goal / max(self.iterations, 1)


def _ours(problem: Problem, settings: KinoSettings) -> Outcome:
    if problem.vehicle == "diffdrive":
        result = dd.plan_diffdrive(problem.world, problem.start, problem.goal, settings,
                                   margin=problem.margin)
    else:
        result = quad.plan_quadrotor(problem.world, problem.start, problem.goal, settings,
                                     margin=problem.margin)
    return _outcome(result)


def _outcome(result: KinoResult) -> Outcome:
    if not result.solved:
        return Outcome(math.inf, result.iterations, len(result.tree_states), math.inf)
    return Outcome(result.time_to_goal, result.iterations, len(result.tree_states),
                   result.duration)


# ------------------------------------------------------------------------ OMPL
@dataclass(frozen=True)
class OmplVehicle:
    """A vehicle as OMPL sees it.

    Attributes:
        space: the state space, bounds set.
        control_lower: (c,) lowest control.
        control_upper: (c,) highest control.
        read: an OMPL state -> its coordinates (d,).
        write: set an OMPL state to coordinates (d,).
        motion: ``motion(state (d,), control (c,))``: the end state (d,) of the control
            held for the settings' duration, or ``None`` when the motion is invalid.
        start: (d,) start state.
        goal: (p,) goal position: the first p coordinates of a state are its position.
        sample_goal: ``sample_goal(rng)``: a state (d,) at the goal position.
    """

    space: object
    control_lower: FloatArray
    control_upper: FloatArray
    read: Callable[[object], FloatArray]
    write: Callable[[object, FloatArray], None]
    motion: Callable[[FloatArray, FloatArray], FloatArray | None]
    start: FloatArray
    goal: FloatArray
    sample_goal: Callable[[np.random.Generator], FloatArray]


def _bounds(lower: FloatArray, upper: FloatArray):
    from ompl import base as ob

    bounds = ob.RealVectorBounds(len(lower))
    bounds.low = [float(v) for v in lower]
    bounds.high = [float(v) for v in upper]
    return bounds


def diffdrive_for_ompl(problem: Problem, settings: KinoSettings) -> OmplVehicle:
    """The robot on SE(2) over the search world's boundary; motions by
    :func:`~quadnav.kinodynamic.diffdrive.track` checked as ``plan_diffdrive`` checks them."""
    from ompl import base as ob

    model = dd.DiffDrive()
    free, start, _, goal_leg = dd.check_query(problem.world, problem.start, problem.goal,
                                              model, problem.margin)
    goal = goal_leg[0]
    space = ob.SE2StateSpace()
    space.setBounds(_bounds(free.lower, free.upper))

    def read(state) -> FloatArray:
        return np.array([state.getX(), state.getY(), state.getYaw()])

    def write(state, values: FloatArray) -> None:
        state.setX(float(values[0]))
        state.setY(float(values[1]))
        state.setYaw(float(values[2]))

    def motion(state: FloatArray, control: FloatArray) -> FloatArray | None:
        xy = dd.track(state, control, settings.duration, dd.CHORD_TOLERANCE)[:, :2]
        chords = np.stack([xy[:-1], xy[1:]], axis=1)
        return dd.propagate(state, control, settings.duration) if free.segments_free(
            chords).all() else None

    def sample_goal(rng: np.random.Generator) -> FloatArray:
        return np.array([*goal, rng.uniform(-math.pi, math.pi)])

    return OmplVehicle(space, np.array([model.v_min, -model.omega_max]),
                       np.array([model.v_max, model.omega_max]), read, write, motion, start,
                       goal, sample_goal)


def quadrotor_for_ompl(problem: Problem, settings: KinoSettings) -> OmplVehicle:
    """The quadrotor on R^6 (position in the search world's boundary, each velocity
    component within the speed limit); motions by
    :func:`~quadnav.kinodynamic.pointmass.exact_states`, checked as ``plan_quadrotor``
    checks them."""
    from ompl import base as ob

    model = SampledQuadrotor()
    free = problem.world.inflate(problem.margin + quad.CHORD_TOLERANCE)
    chord_times = np.linspace(0.0, settings.duration,
                              model.chord_pieces(settings.duration, quad.CHORD_TOLERANCE) + 1)
    speed = model.speed_limit
    space = ob.RealVectorStateSpace(6)
    space.setBounds(_bounds(np.concatenate([free.lower, [-speed] * 3]),
                            np.concatenate([free.upper, [speed] * 3])))

    def read(state) -> FloatArray:
        return np.array(state[0:6])

    def write(state, values: FloatArray) -> None:
        state[0:6] = [float(v) for v in values]

    def motion(state: FloatArray, control: FloatArray) -> FloatArray | None:
        acceleration = model.acceleration(control)
        end = exact_states(state, acceleration, settings.duration)
        if np.linalg.norm(end[3:]) > speed:
            return None
        points = exact_positions(state, acceleration, chord_times)
        return end if free.segments_free(np.stack([points[:-1], points[1:]], axis=1)).all() \
            else None

    at_rest = np.zeros(3)
    return OmplVehicle(space, model.control_lower, model.control_upper, read, write, motion,
                       np.array([*problem.start, *at_rest]), np.array(problem.goal),
                       lambda rng: np.array([*problem.goal, *at_rest]))


def plan_ompl_rrt(problem: Problem, settings: KinoSettings, goal_bias: float) -> Outcome:
    """OMPL's control-based RRT on ``problem`` (see the module docstring)."""
    from ompl import base as ob
    from ompl import control as oc
    from ompl import util as ou

    from quadnav.planning.ompl_planners import _ompl_seed, _quiet

    class PositionGoal(ob.GoalSampleableRegion):
        """States whose position lies within the goal radius of the goal."""

        def __init__(self, si, vehicle: OmplVehicle, rng: np.random.Generator) -> None:
            super().__init__(si)
            self.setThreshold(settings.goal_radius)
            self._vehicle, self._rng = vehicle, rng

        def distanceGoal(self, state) -> float:  # noqa: N802 (OMPL's name)
            goal = self._vehicle.goal
            return float(np.linalg.norm(self._vehicle.read(state)[:len(goal)] - goal))

        def sampleGoal(self, state) -> None:  # noqa: N802 (OMPL's name)
            self._vehicle.write(state, self._vehicle.sample_goal(self._rng))

        def maxSampleCount(self) -> int:  # noqa: N802 (OMPL's name)
            return 1

    make = diffdrive_for_ompl if problem.vehicle == "diffdrive" else quadrotor_for_ompl
    extensions = 0
    with _quiet():
        ou.RNG.setSeed(_ompl_seed(settings.seed))
        vehicle = make(problem, settings)
        controls = oc.RealVectorControlSpace(vehicle.space, len(vehicle.control_lower))
        controls.setBounds(_bounds(vehicle.control_lower, vehicle.control_upper))
        si = oc.SpaceInformation(vehicle.space, controls)

        def propagate(state, control, duration, result) -> None:
            nonlocal extensions
            extensions += 1
            u = np.array([control[i] for i in range(len(vehicle.control_lower))])
            end = vehicle.motion(vehicle.read(state), u)
            vehicle.write(result, np.full(len(vehicle.start), math.nan) if end is None else end)

        si.setStatePropagator(propagate)
        si.setStateValidityChecker(lambda state: math.isfinite(vehicle.read(state)[0]))
        si.setPropagationStepSize(settings.duration)
        si.setMinMaxControlDuration(1, 1)
        si.setup()
        pdef = ob.ProblemDefinition(si)
        start = si.allocState()
        vehicle.write(start, vehicle.start)
        pdef.addStartState(start)
        pdef.setGoal(PositionGoal(si, vehicle, np.random.default_rng(settings.seed)))
        planner = oc.RRT(si)
        planner.setGoalBias(goal_bias)
        planner.setProblemDefinition(pdef)
        planner.setup()
        clock = time.perf_counter()
        planner.solve(ob.timedPlannerTerminationCondition(settings.time_limit))
        seconds = time.perf_counter() - clock
        data = ob.PlannerData(si)
        planner.getPlannerData(data)
        nodes = data.numVertices()
        reached = pdef.hasExactSolution()
        duration = pdef.getSolutionPath().length() if reached else math.inf
    return Outcome(seconds if reached else math.inf, extensions, nodes, duration)


# ------------------------------------------------------------------- measuring
@dataclass
class Figures:
    """Per-seed outcomes of one problem: ``runs[planner]`` in seed order."""

    problem: Problem
    runs: dict[str, list[Outcome]] = field(default_factory=dict)

    def values(self, planner: str, name: str) -> list[float]:
        """One figure (an :class:`Outcome` field) of every run of ``planner``."""
        return [float(getattr(o, name)) for o in self.runs.get(planner, [])]


def runners(settings: KinoSettings, with_ompl: bool
            ) -> dict[str, Callable[[Problem, int], Outcome]]:
    """Planner label -> ``run(problem, seed)``."""
    def seeded(seed: int, **changes: object) -> KinoSettings:
        return settings.replace(seed=seed, **changes)

    found: dict[str, Callable[[Problem, int], Outcome]] = {
        OURS: lambda p, s: _ours(p, seeded(s)),
        OURS_K1: lambda p, s: _ours(p, seeded(s, controls_per_extension=1)),
    }
    if with_ompl:
        for label, bias in OMPL_GOAL_BIAS.items():
            found[label] = (lambda b: lambda p, s: plan_ompl_rrt(p, seeded(s), b))(bias)
    return found


def measure(problem: Problem, seeds: int, settings: KinoSettings, with_ompl: bool
            ) -> Figures:
    """Every planner on ``problem`` for ``seeds`` seeds, after one warm-up run each."""
    figures = Figures(problem)
    run = runners(settings, with_ompl)
    for planner in run.values():
        planner(problem, WARM_UP_SEED)
    for seed in range(seeds):
        print(f"  {problem.label}: seed {seed + 1}/{seeds}", file=sys.stderr, flush=True)
        for label, planner in run.items():
            figures.runs.setdefault(label, []).append(planner(problem, seed))
    return figures


# ------------------------------------------------------------------- reporting
def report(all_figures: list[Figures], settings: KinoSettings) -> str:
    """Three markdown tables: time to the goal region with ratios to ours; the same runs'
    iterations, tree states and plan durations; their wall time per extension."""
    names = list(all_figures[0].runs)
    time_rows, size_rows, cost_rows = [], [], []
    for f in all_figures:
        times = {n: median(f.values(n, "time_to_goal")) for n in names}
        time_rows.append(
            [f.problem.label]
            + [f"{cell(times[n], 3, settings.time_limit)} "
               f"({solved(f.values(n, 'time_to_goal'))})" for n in names]
            + [ratio(times[n], times[OURS], settings.time_limit) for n in names[1:]])
        size_rows.append(
            [f.problem.label]
            + [f"{cell(median(f.values(n, 'iterations')), 3)} / "
               f"{cell(median(f.values(n, 'nodes')), 3)} / "
               f"{cell(median(f.values(n, 'duration')), 3)}" for n in names])
        cost_rows.append([f.problem.label]
                         + [cell(median(f.values(n, "extension_us")), 3) for n in names])
    runs = len(all_figures[0].runs[OURS])
    return "\n".join([
        f"## Time to reach the goal region, s (median of {runs} seeds, limit "
        f"{settings.time_limit:g} s; found/runs)",
        "",
        table(["problem", *names, *(f"{n}/ours" for n in names[1:])], time_rows),
        "",
        "## The same runs: extensions tried / tree states / plan duration in s (medians)",
        "",
        table(["problem", *names], size_rows),
        "",
        "## The same runs: wall time per extension tried, us (median; ours samples 10 "
        "controls per extension, the others 1)",
        "",
        table(["problem", *names], cost_rows),
    ])


def as_json(all_figures: list[Figures], settings: KinoSettings, seeds: int
            ) -> dict[str, object]:
    """Every per-seed figure and its median; runs that did not reach the goal are
    ``null``."""
    def finite(value: float) -> float | None:
        return value if math.isfinite(value) else None

    return {
        "seeds": seeds, "settings": {k: getattr(settings, k) for k in (
            "time_limit", "goal_radius", "duration", "goal_bias", "controls_per_extension")},
        "problems": [{
            "problem": f.problem.label, "start": list(f.problem.start),
            "goal": list(f.problem.goal), "margin": f.problem.margin,
            "planners": {n: {name: {"median": finite(median(f.values(n, name))),
                                    "runs": [finite(v) for v in f.values(n, name)]}
                             for name in ("time_to_goal", "iterations", "nodes", "duration",
                                          "extension_us")}
                         for n in f.runs}}
            for f in all_figures],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20, help="seeds per planner (20)")
    parser.add_argument("--quick", action="store_true",
                        help="smoke run: 3 seeds and a 5 s limit")
    parser.add_argument("--time-limit", type=float, default=None,
                        help="time limit of each run, s (30; quick 5)")
    parser.add_argument("--json", type=Path, help="also write the figures to this JSON file")
    args = parser.parse_args()

    seeds = 3 if args.quick else args.seeds
    limit = args.time_limit or (5.0 if args.quick else 30.0)
    settings = KinoSettings(time_limit=limit, max_iterations=MAX_ITERATIONS)
    with_ompl = ompl_available()
    if not with_ompl:
        print("OMPL is not installed (pip install 'quadnav[ompl]'): its columns are left out")
    all_figures = [measure(problem, seeds, settings, with_ompl) for problem in problems()]
    print(f"goal radius {settings.goal_radius:g} m, controls held {settings.duration:g} s; "
          "every planner gets the same start, goal, limits and collision check\n")
    print(report(all_figures, settings))
    if args.json:
        args.json.write_text(json.dumps(as_json(all_figures, settings, seeds), indent=2)
                             + "\n", encoding="utf-8")
        print(f"\nfigures written to {args.json}")


if __name__ == "__main__":
    main()
