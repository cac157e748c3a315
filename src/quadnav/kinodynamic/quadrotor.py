"""Kinodynamic RRT for a quadrotor steered by sampled roll, pitch and thrust (3D).

:func:`plan_quadrotor` grows a tree of states ``(x, y, z, vx, vy, vz)`` from the start,
at rest, until a state's position is within ``goal_radius`` of the goal and a closing
stop from it to rest exactly at the goal is free (see below). Each iteration:

1. **Sample** a point: with ``settings.biased`` and probability ``goal_bias``, from a
   Gaussian around the goal whose standard deviation is :data:`GOAL_SPREAD` times the
   distance from the goal to the closest tree state (so the cloud narrows as the tree
   closes in); otherwise uniformly in the boundary box.
2. **Nearest** tree state to the sample by the distance from the sample to where the
   state would drift in :data:`LOOKAHEAD` seconds, ``p + LOOKAHEAD v``: a state already
   moving towards the sample is closer than one moving away.
3. **Extend**: draw ``controls_per_extension`` controls uniformly within the model's
   limits, propagate each exactly for ``settings.duration`` s, prune those that dip to or
   below the floor (boundary ``zmin + margin``, checked exactly on the parabola), end
   faster than the speed limit (``|v + a s|`` is convex in ``s``, so the speed along a
   motion never exceeds its larger end speed) or collide, and add the survivor whose
   end is nearest the sample.
4. **Close**: from a new state inside the goal region, the closing stop: two constant
   accelerations, each held for the same time, that bring it to rest exactly at the goal
   (:func:`~quadnav.kinodynamic.closing.closing_candidates`: the shortest the model can
   fly within its limits and speed limit that stays above the floor and free, checked as
   every motion is). The plan ends with it, so a flight of the plan ends at the goal,
   not merely near it; when no candidate is free the search goes on.

Collision guarantee: every motion is cut into equal pieces (see
:meth:`~quadnav.kinodynamic.pointmass.SampledQuadrotor.chord_pieces`) whose chords are
within :data:`CHORD_TOLERANCE` of the parabola; all chords of an extension are checked
exactly in one batch against the world inflated by ``margin + CHORD_TOLERANCE``. A
point within ``CHORD_TOLERANCE`` of a free chord point is then free in the world
inflated by ``margin`` alone, so every tree edge keeps ``margin`` from every block and
from the boundary along its whole exact motion. The floor check is implied by this one
(the inflated boundary's floor is ``CHORD_TOLERANCE`` higher); done first, exactly and
cheaply, it spares those motions the chord checks and is counted on its own.
"""

from __future__ import annotations

import itertools
import math
import time

import numpy as np
from numpy.typing import ArrayLike, NDArray

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.kinodynamic.closing import closing_candidates
from quadnav.kinodynamic.pointmass import SampledQuadrotor, exact_positions, exact_states
from quadnav.kinodynamic.result import KinoResult
from quadnav.kinodynamic.settings import KinoSettings
from quadnav.kinodynamic.tree import ControlTree
from quadnav.planning.problem import make_problem
from quadnav.planning.result import Progress
from quadnav.world.model import World

#: Largest distance, m, from a tree motion to the chords it is checked by.
CHORD_TOLERANCE = 0.02
#: Acceleration of the straight flight along a leg out of the margin, m/s^2.
LEG_ACCELERATION = 1.0
#: Goal-biased samples have a standard deviation of this times the closest distance.
GOAL_SPREAD = 0.5
#: Nearest-state metric: the sample's distance to ``p + LOOKAHEAD v``, s.
LOOKAHEAD = 0.1
#: Iterations between two calls of ``progress``.
PROGRESS_EVERY = 256
#: Default step of :func:`replay`, s.
REPLAY_STEP = 1e-3
#: How closely :func:`replay` reproduces the planned states (position m, velocity m/s).
#: Measured (largest error of any state component): 7e-12 on 20-40 s flights across the
#: 20 m forest, the window world and map1; 7e-11 on a 170 s flight across a 100 m forest.
REPLAY_TOLERANCE = 1e-9

class _Tree(ControlTree):
    """The tree's arrays and, per vertex, the point :meth:`nearest` measures from."""

    COLUMNS = (*ControlTree.COLUMNS, "keys")

    def __init__(self, start_state: FloatArray) -> None:
        super().__init__(start_state, 3)
        self.keys = np.zeros((len(self.states), 3))
        self.keys[0] = _key(self.states[0])

    def add(self, parent: int, state: FloatArray, control: FloatArray, duration: float
            ) -> int:
        index = super().add(parent, state, control, duration)
        self.keys[index] = _key(state)
        return index

    def nearest(self, point: FloatArray) -> int:
        differences = self.keys[:self.size] - point
        return int(np.argmin(np.einsum("ij,ij->i", differences, differences)))


def _key(state: FloatArray) -> FloatArray:
    return state[:3] + LOOKAHEAD * state[3:]


def plan_quadrotor(world: World, start: ArrayLike, goal: ArrayLike, settings: KinoSettings,
                   model: SampledQuadrotor | None = None, margin: float = 0.2,
                   progress: Progress | None = None, body: ArrayLike = (0.0, 0.0, 0.0)
                   ) -> KinoResult:
    """Plan a flight from ``start`` (at rest) into the ball of ``settings.goal_radius``
    around ``goal`` and on to rest exactly at ``goal`` by kinodynamic RRT (see the module
    docstring).

    Starts and goals are checked as every planner checks them
    (:func:`~quadnav.planning.make_problem`, with the margin plus the chord tolerance): one
    inside the margin is left by its leg, flown straight from rest to rest
    (:func:`leg_motions`) before the tree grows; for a goal inside it, the goal region is
    centred on the end of its leg, the nearest point that keeps the margin, the closing
    stop ends there, and the plan flies the leg into the goal from rest to rest.

    Args:
        world: the map, blocks not inflated.
        start: (3,) start position, m; the vehicle starts at rest.
        goal: (3,) goal position, m.
        settings: budget, seed, sampling and extension settings.
        model: the vehicle; default :class:`SampledQuadrotor()`.
        margin: safety margin, m, >= 0, kept from every block and the boundary.
        progress: called every :data:`PROGRESS_EVERY` iterations and at the end.
        body: half extents (3,) of the vehicle's body box along x, y, z, m (default: a
            point): a start where it does not fit in the boundary is left by the shortest
            move that brings it in, a goal there is moved to the nearest point where it
            fits (:func:`~quadnav.planning.make_problem`).

    Returns:
        A :class:`KinoResult` named ``"quadrotor"``: states (K, 6) position m and velocity
        m/s, the last exactly ``(goal, 0)``, controls (K - 1, 3) ``(phi rad, theta rad,
        T N)``, durations (K - 1,) s (``settings.duration`` each but for the legs and the
        closing stop). ``seconds`` and ``time_to_goal`` count from the start of the
        search, after the start and goal checks and loading the collision kernels.

    Raises:
        QuadnavError: a start or goal outside the boundary or in a block, the start equal
            to the goal, a start or goal the vehicle cannot leave the margin from, or a
            start and goal provably disconnected.
    """
    model = model or SampledQuadrotor()
    if not (math.isfinite(margin) and margin >= 0):
        raise QuadnavError(f"margin must be >= 0 m, got {margin}")
    problem = make_problem(world, start, goal, margin + CHORD_TOLERANCE, body)
    free, goal_point = problem.free_world, problem.search_goal
    free.segments_free(np.zeros((0, 2, 3)))  # load the kernels and the block grid
    clock = time.perf_counter()
    rng = np.random.default_rng(settings.seed)
    tree = _Tree(np.concatenate([problem.start, np.zeros(3)]))
    leg = leg_motions(model, problem.start_leg)
    for state, control, duration in leg:
        tree.add(tree.size - 1, state, control, duration)
    extend = _Extender(model, free, world.lower[2] + margin, settings)
    goal_leg = leg_motions(model, problem.goal_leg)

    def close(index: int) -> int:
        """Add the closing stop from vertex ``index`` and the goal leg; the last vertex
        added, or -1 when no closing stop from it is free."""
        stop = extend.close(tree.states[index], goal_point)
        if stop is None:
            return -1
        for state, control, duration in (*stop, *goal_leg):
            index = tree.add(index, state, control, duration)
        return index

    closest = float(np.linalg.norm(problem.search_start - goal_point))
    reached = close(tree.size - 1) if closest <= settings.goal_radius else -1
    iterations = 0
    time_to_goal = time.perf_counter() - clock if reached >= 0 else None
    while reached < 0 and iterations < settings.max_iterations:
        elapsed = time.perf_counter() - clock
        if elapsed >= settings.time_limit:
            break
        if progress is not None and iterations % PROGRESS_EVERY == 0:
            progress(settings.budget_used(iterations, elapsed), closest)
        iterations += 1
        if settings.biased and rng.random() < settings.goal_bias:
            sample = goal_point + rng.normal(scale=GOAL_SPREAD * closest, size=3)
        else:
            sample = rng.uniform(free.lower, free.upper)
        parent = tree.nearest(sample)
        motion = extend(tree.states[parent], sample, rng)
        if motion is None:
            continue
        end, control = motion
        index = tree.add(parent, end, control, settings.duration)
        distance = float(np.linalg.norm(end[:3] - goal_point))
        closest = min(closest, distance)
        if distance <= settings.goal_radius:
            reached = close(index)
            time_to_goal = time.perf_counter() - clock if reached >= 0 else None
    seconds = time.perf_counter() - clock
    if progress is not None:
        progress(1.0 if reached >= 0 else settings.budget_used(iterations, seconds), closest)
    branch = tree.branch(reached) if reached >= 0 else []
    n = tree.size
    outcome = (f"reached the goal region and closed onto the goal in {iterations} iterations"
               if reached >= 0 else
               f"goal region not reached in {iterations} iterations and {seconds:.2f} s; "
               f"closest {closest:.3g} m from the goal")
    unclosed = (f"; {extend.unclosed} states in the goal region with no free closing stop"
                if extend.unclosed else "")
    return KinoResult(
        planner="quadrotor", solved=reached >= 0,
        states=tree.states[branch].reshape(-1, 6), controls=tree.controls[branch[1:]],
        durations=tree.durations[branch[1:]], tree_states=tree.states[:n],
        tree_parents=tree.parents[:n], tree_controls=tree.controls[:n],
        tree_durations=tree.durations[:n], iterations=iterations, seconds=seconds,
        time_to_goal=time_to_goal, seed=settings.seed,
        message=f"{outcome}; {n} states; motions pruned: "
                + ", ".join(f"{count} {why}" for why, count in extend.pruned.items())
                + unclosed,
        leg_controls=len(leg) if reached >= 0 else 0,
        closing_controls=2 if reached >= 0 else 0,
        goal_leg_controls=len(goal_leg) if reached >= 0 else 0)


class _Extender:
    """One extension: sample controls, propagate them from a state, prune, keep the best;
    and the closing stop from a state in the goal region (:meth:`close`).

    ``pruned`` counts the motions pruned for each reason, ``unclosed`` the states with no
    free closing stop.
    """

    def __init__(self, model: SampledQuadrotor, free: World, floor: float,
                 settings: KinoSettings) -> None:
        self.model, self.free, self.floor = model, free, floor
        self.duration, self.count = settings.duration, settings.controls_per_extension
        pieces = model.chord_pieces(settings.duration, CHORD_TOLERANCE)
        self.chord_times = np.linspace(0.0, settings.duration, pieces + 1)
        self.pruned = {"below the floor": 0, "too fast": 0, "colliding": 0}
        self.unclosed = 0

    def __call__(self, state: FloatArray, sample: FloatArray, rng: np.random.Generator
                 ) -> tuple[FloatArray, FloatArray] | None:
        """``(end state (6,), control (3,))`` of the surviving motion from ``state`` that
        ends nearest ``sample`` (3,), or ``None`` when every motion is pruned."""
        model, pruned = self.model, self.pruned
        controls = model.sample_controls(rng, self.count)
        accelerations = model.acceleration(controls)
        ends = exact_states(state, accelerations, self.duration)
        keep = _lowest_heights(state, accelerations, self.duration) > self.floor
        pruned["below the floor"] += int(np.count_nonzero(~keep))
        if model.speed_limit is not None:
            fast = keep & (np.einsum("ij,ij->i", ends[:, 3:], ends[:, 3:])
                           > model.speed_limit**2)
            pruned["too fast"] += int(np.count_nonzero(fast))
            keep &= ~fast
        candidates = np.flatnonzero(keep)
        if candidates.size:
            clear = _motions_free(self.free, state, accelerations[candidates],
                                  self.chord_times)
            pruned["colliding"] += int(np.count_nonzero(~clear))
            candidates = candidates[clear]
        if candidates.size == 0:
            return None
        best = candidates[np.argmin(np.linalg.norm(ends[candidates, :3] - sample, axis=1))]
        return ends[best], controls[best]

    def close(self, state: FloatArray, goal: FloatArray
              ) -> list[tuple[FloatArray, FloatArray, float]] | None:
        """The closing stop from ``state`` (6,) to rest at ``goal`` (3,), as its two
        motions (end state (6,), control (3,), duration s), the last ending exactly at
        ``(goal, 0)``: the shortest candidate (:func:`closing_candidates`) whose pieces
        stay above the floor and are free (all chords of all candidates in one batch);
        ``None`` when there is none."""
        halves, controls = closing_candidates(self.model, state, goal)
        accelerations = self.model.acceleration(controls)  # (n, 2, 3)
        middles = exact_states(state, accelerations[:, 0], halves)
        starts = np.concatenate([np.broadcast_to(state, middles.shape), middles])
        pieces = np.concatenate([accelerations[:, 0], accelerations[:, 1]])
        durations = np.concatenate([halves, halves])
        fine = _lowest_heights(starts, pieces, durations) > self.floor
        if halves.size:
            steps = self.model.chord_pieces(float(halves.max()), CHORD_TOLERANCE)
            chord_times = durations[:, None] * np.linspace(0.0, 1.0, steps + 1)
            fine &= _motions_free(self.free, starts, pieces, chord_times)
        usable = np.flatnonzero(fine.reshape(2, -1).all(axis=0))
        if usable.size == 0:
            self.unclosed += 1
            return None
        best, half = usable[0], float(halves[usable[0]])
        return [(middles[best], controls[best, 0], half),
                (np.concatenate([goal, np.zeros(3)]), controls[best, 1], half)]


def leg_motions(model: SampledQuadrotor, leg: FloatArray
                ) -> list[tuple[FloatArray, FloatArray, float]]:
    """The motions (end state (6,), control (3,), duration s) that fly the polyline ``leg``
    (K, 3) straight, each segment from rest to rest: full acceleration along it for half
    the time, full deceleration for the other half (at most :data:`LEG_ACCELERATION`,
    less where the limits or the speed limit ask)."""
    motions = []
    for begin, end in itertools.pairwise(np.asarray(leg, dtype=np.float64)):
        length = float(np.linalg.norm(end - begin))
        direction = (end - begin) / length
        rate = LEG_ACCELERATION
        if model.speed_limit is not None:
            rate = min(rate, 0.9 * model.speed_limit**2 / length)
        while (model.control_for(rate * direction) is None
               or model.control_for(-rate * direction) is None):
            rate /= 2.0
        half = math.sqrt(length / rate)
        middle = np.concatenate([0.5 * (begin + end), rate * half * direction])
        motions.append((middle, model.control_for(rate * direction), half))
        motions.append((np.concatenate([end, np.zeros(3)]), model.control_for(-rate * direction),
                        half))
    return motions


def _motions_free(free: World, state: FloatArray, accelerations: FloatArray,
                  chord_times: FloatArray) -> NDArray[np.bool_]:
    """Whether each motion from ``state`` (6,) or states (n, 6) under accelerations (n, 3)
    is free: all its chords between the positions at ``chord_times`` (P + 1,) or
    (n, P + 1) s, in one batch -> (n,)."""
    points = exact_positions(state, accelerations, chord_times)  # (n, P + 1, 3)
    pieces = points.shape[1] - 1
    chords = np.empty((len(points), pieces, 2, 3))
    chords[:, :, 0], chords[:, :, 1] = points[:, :-1], points[:, 1:]
    return free.segments_free(chords.reshape(-1, 2, 3)).reshape(-1, pieces).all(axis=1)


def _lowest_heights(state: FloatArray, accelerations: FloatArray,
                    duration: float | FloatArray) -> FloatArray:
    """Lowest z (n,), m, along each exact motion from ``state`` (6,) or states (n, 6) under
    accelerations (n, 3) held for ``duration`` s (a scalar or (n,)): an end, or the
    vertex of the parabola within it."""
    z, vz, az = state[..., 2], state[..., 5], accelerations[:, 2]
    end = z + vz * duration + 0.5 * az * duration**2
    lowest = np.minimum(z, end)
    with np.errstate(divide="ignore", invalid="ignore"):
        vertex_time = -vz / az
    inside = (az > 0) & (vertex_time > 0) & (vertex_time < duration)
    return np.where(inside, np.minimum(lowest, z - 0.5 * vz * vz / np.where(inside, az, 1.0)),
                    lowest)



def replay(model: SampledQuadrotor, start_state: ArrayLike, controls: ArrayLike,
           durations: ArrayLike, dt: float = REPLAY_STEP) -> tuple[FloatArray, FloatArray]:
    """Fly a control sequence open loop through the vehicle dynamics, by fixed-step RK4.

    This integrates the ODE ``p' = v``, ``v' = a(control)`` independently of the exact
    propagation the planner uses. Each control is held for its duration, cut into
    ``ceil(duration / dt)`` equal steps, so every control change falls on a step. RK4 is
    exact for this piecewise-constant acceleration, so the replay reproduces the planned
    states to round-off: within :data:`REPLAY_TOLERANCE` = 1e-9 (measured: 7e-12 on a
    30 s flight, 7e-11 on a 170 s one; round-off grows with the number of steps).

    This checks the planner's own propagation; flying the plan on the full 6-DOF vehicle,
    closed loop, is :func:`quadnav.kinoflight.fly_kino_plan`.

    Args:
        model: the vehicle.
        start_state: (6,) position m and velocity m/s.
        controls: (K, 3) ``(phi rad, theta rad, T N)``.
        durations: (K,) s each control is held.
        dt: largest step, s, > 0.

    Returns:
        ``(t, states)``: times (N,) s from 0 and states (N, 6). The planned states'
        times, ``[0, cumsum(durations)]``, are among ``t`` exactly.
    """
    if not (math.isfinite(dt) and dt > 0):
        raise QuadnavError(f"replay step must be > 0 s, got {dt}")
    state = np.array(start_state, dtype=np.float64)
    u = np.asarray(controls, dtype=np.float64).reshape(-1, 3)
    times, states = [np.zeros(1)], [state[None]]
    begin = 0.0
    for control, duration in zip(u, np.asarray(durations, dtype=np.float64), strict=True):
        acceleration = model.acceleration(control)
        steps = max(1, math.ceil(duration / dt))
        h = duration / steps
        flown = np.empty((steps, 6))
        for i in range(steps):
            state = _rk4_step(state, acceleration, h)
            flown[i] = state
        times.append(begin + duration * np.arange(1, steps + 1) / steps)
        states.append(flown)
        begin += duration
    return np.concatenate(times), np.concatenate(states)


def _derivative(state: FloatArray, acceleration: FloatArray) -> FloatArray:
    return np.concatenate([state[3:], acceleration])


def _rk4_step(state: FloatArray, acceleration: FloatArray, h: float) -> FloatArray:
    k1 = _derivative(state, acceleration)
    k2 = _derivative(state + 0.5 * h * k1, acceleration)
    k3 = _derivative(state + 0.5 * h * k2, acceleration)
    k4 = _derivative(state + h * k3, acceleration)
    return state + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
