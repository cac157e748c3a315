"""A differential-drive robot and its kinodynamic RRT: :class:`DiffDrive`, :func:`plan_diffdrive`.

Model
-----
State ``(x, y, theta)``: the centre between the wheels (m) and the heading (rad, from +x
towards +y, kept in ``[-pi, pi)``). Control ``(v, omega)``: forward speed of the centre
(m/s) and turn rate (rad/s, positive turns left), held constant over each edge. The
unicycle ``x' = v cos theta, y' = v sin theta, theta' = omega`` is integrated exactly
(:func:`propagate`): the centre moves on a circular arc, or a straight line when
``omega = 0``, with no integration error.

The wheels sit at ``centre +/- (b/2) (-sin theta, cos theta)`` (``+``: left wheel), and
roll at ``v - omega b/2`` (left) and ``v + omega b/2`` (right), m/s.

Collision checking
------------------
The robot is a disc of :attr:`DiffDrive.radius`. Each motion is sampled at equal time
steps so that every chord between consecutive samples deviates from the arc by at most
:data:`CHORD_TOLERANCE` (:func:`segments_needed`); each chord is checked exactly
against the world inflated by ``radius + margin + CHORD_TOLERANCE``. Every point of the
arc is within the tolerance of a checked chord, so the whole disc swept along the arc
stays clear of the obstacles inflated by ``margin`` (inflation by squares contains
inflation by discs): edges are collision-free along their integrated motion, not just at
their samples.
"""

from __future__ import annotations

import itertools
import math
import time
import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from quadnav.arrays import FloatArray
from quadnav.config import require
from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.kinodynamic.result import KinoResult
from quadnav.kinodynamic.settings import KinoSettings
from quadnav.kinodynamic.tree import ControlTree
from quadnav.kinodynamic.world2d import World2D, format_rect
from quadnav.planning.legs import find_leg
from quadnav.planning.result import Progress, path_length

NAME = "diffdrive"
#: Largest distance between a checked chord and the arc it stands for, metres.
CHORD_TOLERANCE = 0.01
#: Speed along a leg out of the margin, m/s.
LEG_SPEED = 0.5
#: Standard deviation of goal-biased samples per metre between the goal and the tree's
#: closest state.
GOAL_SPREAD = 0.5
#: Wall time between two progress reports, s.
PROGRESS_SECONDS = 0.1


@dataclass(frozen=True)
class DiffDrive:
    """Geometry and limits of a differential-drive robot.

    Attributes:
        wheel_base: distance between the wheels ``b``, m, > 0.
        v_min: lowest forward speed, m/s (negative: it may reverse).
        v_max: highest forward speed, m/s, > ``v_min``.
        omega_max: turn rate limit, rad/s, > 0: ``|omega| <= omega_max``.
        radius: radius of the robot's footprint, m, >= 0; obstacles are inflated by it.
    """

    wheel_base: float = 0.3
    v_min: float = -0.2
    v_max: float = 1.0
    omega_max: float = 1.5
    radius: float = 0.2

    def __post_init__(self) -> None:
        values = (self.wheel_base, self.v_min, self.v_max, self.omega_max, self.radius)
        checks = [
            (all(math.isfinite(v) for v in values), "model parameters must be finite"),
            (self.wheel_base > 0, f"wheel base must be > 0 m, got {self.wheel_base}"),
            (self.v_min < self.v_max,
             f"speed limits must have v_min < v_max, got {self.v_min} >= {self.v_max}"),
            (self.omega_max > 0, f"turn rate limit must be > 0 rad/s, got {self.omega_max}"),
            (self.radius >= 0, f"robot radius must be >= 0 m, got {self.radius}"),
        ]
        require(checks)

    def sample_controls(self, rng: np.random.Generator, n: int) -> FloatArray:
        """``n`` controls (n, 2) ``(v, omega)`` drawn uniformly within the limits."""
        return rng.uniform((self.v_min, -self.omega_max), (self.v_max, self.omega_max),
                           size=(n, 2))

    def wheel_speeds(self, controls: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Left and right wheel speeds, m/s, of controls (..., 2): ``v -/+ omega b/2``."""
        c = np.asarray(controls, dtype=np.float64)
        half_turn = 0.5 * self.wheel_base * c[..., 1]
        return c[..., 0] - half_turn, c[..., 0] + half_turn

    def wheel_positions(self, states: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Left and right wheel contact points (..., 2) of states (..., 3), metres."""
        s = np.asarray(states, dtype=np.float64)
        offset = 0.5 * self.wheel_base * np.stack([-np.sin(s[..., 2]), np.cos(s[..., 2])],
                                                  axis=-1)
        return s[..., :2] + offset, s[..., :2] - offset


# ------------------------------------------------------------------ integration
def wrap_angle(angle: ArrayLike) -> FloatArray:
    """Angles (rad) wrapped into ``[-pi, pi)``."""
    return np.mod(np.asarray(angle, dtype=np.float64) + np.pi, 2 * np.pi) - np.pi


def propagate(states: ArrayLike, controls: ArrayLike, t: ArrayLike) -> FloatArray:
    """Exact unicycle motion: the states reached by holding each control for ``t``.

    ``x(t) = x + v t sinc(omega t / 2) cos(theta + omega t / 2)`` (likewise ``y`` with
    ``sin``), ``theta(t) = theta + omega t`` wrapped into ``[-pi, pi)``, where
    ``sinc(a) = sin(a) / a``: the closed-form arc, numerically stable as ``omega -> 0``
    (no division by ``omega``).

    Args:
        states: (..., 3) ``(x, y, theta)``, m and rad.
        controls: (..., 2) ``(v, omega)``, m/s and rad/s.
        t: seconds, broadcast against the leading dimensions (a scalar, or e.g. (n,)).

    Returns:
        (..., 3) states after ``t``.
    """
    s = np.asarray(states, dtype=np.float64)
    c = np.asarray(controls, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)
    turn = c[..., 1] * t
    heading = s[..., 2] + 0.5 * turn
    chord = c[..., 0] * t * np.sinc(turn / (2 * np.pi))  # np.sinc(u) = sin(pi u) / (pi u)
    return np.stack([s[..., 0] + chord * np.cos(heading), s[..., 1] + chord * np.sin(heading),
                     wrap_angle(s[..., 2] + turn)], axis=-1)


def segments_needed(controls: ArrayLike, durations: ArrayLike, tolerance: float,
                    reach: float = 0.0) -> NDArray[np.int64]:
    """Equal time steps per motion so every chord stays within ``tolerance`` of its arc.

    A point at distance ``r`` from the centre of turn moves on a circle; a chord across
    an angle ``a <= pi`` of it deviates from the arc by at most the sagitta
    ``r (1 - cos(a / 2)) = 2 r sin^2(a / 4)``. Points rigidly attached within ``reach``
    metres of the robot's centre (e.g. the wheels, ``reach = b / 2``) turn on circles of
    radius at most ``|v / omega| + reach``, so the step angle is kept below
    ``4 arcsin(sqrt(tolerance / (2 (|v / omega| + reach))))`` and below ``pi``.

    Args:
        controls: (n, 2) ``(v, omega)``.
        durations: (n,) or a scalar, seconds each control is held.
        tolerance: largest chord-to-arc deviation, m, > 0.
        reach: distance from the centre of the points that must be tracked too, m.

    Returns:
        (n,) number of chords, >= 1.
    """
    c = np.asarray(controls, dtype=np.float64).reshape(-1, 2)
    speed, rate = np.abs(c[:, 0]), np.abs(c[:, 1])
    angle = rate * np.asarray(durations, dtype=np.float64)
    circle_speed = speed + reach * rate  # turn radius times the turn rate
    ratio = np.divide(tolerance * rate, 2 * circle_speed, out=np.full_like(rate, np.inf),
                      where=circle_speed > 0)
    # Slightly smaller than the bound, so rounding in ceil() never gives too few steps.
    step = 4 * np.arcsin(np.sqrt(np.minimum(ratio, 0.5))) * (1 - 1e-9)
    count = np.divide(angle, step, out=np.ones_like(angle), where=step > 0)
    return np.maximum(np.ceil(count), 1).astype(np.int64)


def arc_samples(states: ArrayLike, controls: ArrayLike, durations: ArrayLike,
                segments: int) -> FloatArray:
    """States (n, segments + 1, 3) at equal time steps along each motion, both ends
    included; the last is exactly ``propagate(states, controls, durations)``.

    Args:
        states: (n, 3) where each motion starts.
        controls: (n, 2) ``(v, omega)`` held.
        durations: (n,) or a scalar, seconds.
        segments: time steps per motion, >= 1.
    """
    s = np.asarray(states, dtype=np.float64).reshape(-1, 3)
    c = np.asarray(controls, dtype=np.float64).reshape(-1, 2)
    fractions = np.arange(segments + 1) / segments
    times = np.reshape(durations, (-1, 1)) * fractions
    return propagate(s[:, None, :], c[:, None, :], times)


def track(state: ArrayLike, control: ArrayLike, duration: float, tolerance: float,
          reach: float = 0.0) -> FloatArray:
    """Samples (k, 3) along one motion, both ends included, whose chords deviate from the
    arc by at most ``tolerance`` metres (also for points up to ``reach`` m from the
    centre; see :func:`segments_needed`)."""
    count = int(segments_needed(np.reshape(control, (1, 2)), duration, tolerance, reach)[0])
    return arc_samples(np.reshape(state, (1, 3)), np.reshape(control, (1, 2)), duration,
                       count)[0]


# ---------------------------------------------------------------------- planning
def _check_end(world: World2D, free: World2D, point: FloatArray, label: str,
               clearance: str) -> None:
    """QuadnavError unless ``point`` (2,) is free in the inflated world ``free``."""
    where = f"{world.name}: {label} ({point[0]:.4g}, {point[1]:.4g})"
    if not world.in_boundary(point):
        raise QuadnavError(f"{where} is outside the boundary {format_rect(world.boundary)}")
    if free.is_free(point):
        return
    inside = free.rects_containing(point)
    if inside.size:
        rects = ", ".join(f"rect {i} {format_rect(world.rects[i])}" for i in inside)
        raise QuadnavError(f"{where} is within {clearance} of {rects}")
    raise QuadnavError(f"{where} is within {clearance} of the boundary")


def check_query(world: World2D, start: ArrayLike, goal: ArrayLike, model: DiffDrive,
                margin: float) -> tuple[World2D, FloatArray, FloatArray, FloatArray]:
    """The world the search runs in, the start (3,), the start's leg (K, 2) and the goal's
    (J, 2).

    The search world is ``world`` inflated by ``radius + margin + CHORD_TOLERANCE``. A
    start or goal whose footprint (the disc plus the tolerance) crosses the boundary or a
    rectangle is a QuadnavError naming it; one inside the margin is usable, as for every
    planner (:func:`quadnav.planning.legs.find_leg`): the robot leaves the margin by its
    leg, from the start out of the margin, and enters it by the goal's, from a point that
    keeps the margin to the goal; a free start's or goal's leg is just the point.
    """
    start = np.array(start, dtype=np.float64)
    goal = np.array(goal, dtype=np.float64)
    if start.shape != (3,) or not np.all(np.isfinite(start)):
        raise QuadnavError(f"start: expected 3 finite numbers x y theta, got {start.tolist()}")
    if goal.shape != (2,) or not np.all(np.isfinite(goal)):
        raise QuadnavError(f"goal: expected 2 finite numbers x y, got {goal.tolist()}")
    if not (math.isfinite(margin) and margin >= 0):
        raise QuadnavError(f"margin must be >= 0 m, got {margin}")
    body = world.inflate(model.radius + CHORD_TOLERANCE)
    free = body.inflate(margin)
    footprint = (f"{model.radius + CHORD_TOLERANCE:g} m (robot radius {model.radius:g} m + "
                 f"tolerance {CHORD_TOLERANCE:g} m)")
    _check_end(world, body, start[:2], "start", footprint)
    _check_end(world, body, goal, "goal", footprint)
    if np.array_equal(start[:2], goal):
        raise QuadnavError(f"start and goal are the same point ({goal[0]:.4g}, {goal[1]:.4g}):"
                           " there is nothing to drive; give a different --goal")
    start_leg, goal_leg = (_leg(body, margin, point, label) for point, label in (
        (start[:2], "start"), (goal, "goal")))
    start[2] = wrap_angle(start[2])
    return free, start, start_leg, goal_leg[::-1]


def _leg(body: World2D, margin: float, point: FloatArray, label: str) -> FloatArray:
    """The leg (K, 2) out of the margin from ``point`` (2,), a free point of ``body``
    (the world inflated by the footprint); just the point when it keeps the margin.

    The 2D world is lifted to 3D, each rectangle a box across a slab thicker than the
    margin, so the 3D legs apply; the slab's floor and ceiling are never the way out."""
    lifted = body.lifted(margin + 1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)
        leg = find_leg(lifted, lifted.inflate(margin), np.array([*point, 0.0]), margin, label)
    if len(leg) > 1:
        warnings.warn(f"{label} ({point[0]:.4g}, {point[1]:.4g}) is inside the {margin:g} m "
                      f"safety margin; only the {path_length(leg):.3g} m leg "
                      f"{'out of' if label == 'start' else 'into'} it may come closer",
                      PlanningWarning, stacklevel=4)
    return leg[:, :2]


def leg_motions(model: DiffDrive, heading: float, leg: FloatArray
                ) -> list[tuple[FloatArray, FloatArray, float]]:
    """The motions (end state (3,), control (2,), duration s) that drive the polyline
    ``leg`` (K, 2) from ``heading`` rad: at each vertex turn on the spot at the full turn
    rate to face the next one, then drive straight to it at :data:`LEG_SPEED` (or the top
    speed, if lower)."""
    motions = []
    speed = min(LEG_SPEED, model.v_max)
    for begin, end in itertools.pairwise(np.asarray(leg, dtype=np.float64)):
        towards = math.atan2(end[1] - begin[1], end[0] - begin[0])
        turn = float(wrap_angle(towards - heading))
        if turn != 0.0:
            motions.append((np.array([*begin, towards]),
                            np.array([0.0, math.copysign(model.omega_max, turn)]),
                            abs(turn) / model.omega_max))
        motions.append((np.array([*end, towards]), np.array([speed, 0.0]),
                        float(np.linalg.norm(end - begin)) / speed))
        heading = towards
    return motions


def _sample_target(rng: np.random.Generator, settings: KinoSettings, free: World2D,
                   goal: FloatArray, closest: float) -> FloatArray:
    """The point (2,) the tree grows towards: with ``settings.biased``, with probability
    ``goal_bias`` a Gaussian around the goal of standard deviation ``GOAL_SPREAD`` times
    the distance from the goal to the closest tree state; otherwise uniform in the
    boundary."""
    if settings.biased and rng.random() < settings.goal_bias:
        return goal + rng.normal(0.0, GOAL_SPREAD * closest, size=2)
    return rng.uniform(free.lower, free.upper)


def _extend(free: World2D, state: FloatArray, controls: FloatArray, duration: float
            ) -> tuple[FloatArray, NDArray[np.bool_]]:
    """End states (n, 3) of the controls (n, 2) held from ``state`` for ``duration``, and
    whether each motion is collision-free (all chords checked in one batch)."""
    n = len(controls)
    count = int(segments_needed(controls, duration, CHORD_TOLERANCE).max())
    samples = arc_samples(np.broadcast_to(state, (n, 3)), controls, duration, count)
    xy = samples[..., :2]
    chords = np.stack([xy[:, :-1], xy[:, 1:]], axis=2).reshape(-1, 2, 2)
    free_motion = free.segments_free(chords).reshape(n, count).all(axis=1)
    return samples[:, -1], free_motion


def plan_diffdrive(world: World2D, start: ArrayLike, goal: ArrayLike, settings: KinoSettings,
                   model: DiffDrive | None = None, margin: float = 0.0,
                   progress: Progress | None = None) -> KinoResult:
    """Kinodynamic RRT for a differential-drive robot.

    Each iteration draws a target point (:func:`_sample_target`), takes the tree state
    nearest it in (x, y), samples ``settings.controls_per_extension`` controls within the
    model's limits, integrates each for ``settings.duration`` exactly, drops those whose
    motion collides, and adds the end nearest the target. The search stops when a state
    lies within ``settings.goal_radius`` of the goal or the iteration or time budget ends.
    For a goal inside the margin, the goal region is centred on the end of its leg (the
    nearest point that keeps the margin), and the plan ends by driving straight from the
    state reached there to that point (when the drive is free; else the search goes on)
    and along the leg into the goal (:func:`leg_motions`), so every plan ends within the
    goal radius of the goal asked for.

    Args:
        world: the map, rectangles not inflated.
        start: (3,) ``(x, y, theta)``, m and rad.
        goal: (2,) ``(x, y)`` centre of the goal region, m.
        settings: budgets, seed, sampling.
        model: the robot; ``None``: :class:`DiffDrive` defaults.
        margin: safety margin kept around the robot's footprint, m, >= 0.
        progress: called about every :data:`PROGRESS_SECONDS` (see
            :data:`~quadnav.planning.result.Progress`).

    Returns:
        A :class:`KinoResult` named ``"diffdrive"``: states (K, 3), controls (K - 1, 2)
        ``(v, omega)``, durations (K - 1,), and the whole tree.
    """
    model = model or DiffDrive()
    free, start, leg, goal_leg = check_query(world, start, goal, model, margin)
    goal = goal_leg[0]
    clock = time.perf_counter()
    rng = np.random.default_rng(settings.seed)
    motions = leg_motions(model, float(start[2]), leg)
    tree = ControlTree(start, 2, capacity=settings.max_iterations + 1 + len(motions))
    for state, control, duration in motions:
        tree.add(tree.size - 1, state, control, duration)
    closing = _Closing(free, model, goal_leg)
    closest = float(np.hypot(*(tree.states[tree.size - 1, :2] - goal)))
    reached = closing(tree, tree.size - 1) if closest <= settings.goal_radius else -1
    iterations, reported = 0, 0.0
    elapsed = time.perf_counter() - clock
    while reached < 0 and iterations < settings.max_iterations and elapsed < settings.time_limit:
        iterations += 1
        target = _sample_target(rng, settings, free, goal, closest)
        gaps = tree.states[:tree.size, :2] - target
        near = int(np.argmin(np.einsum("ij,ij->i", gaps, gaps)))
        controls = model.sample_controls(rng, settings.controls_per_extension)
        ends, ok = _extend(free, tree.states[near], controls, settings.duration)
        if ok.any():
            candidates = np.flatnonzero(ok)
            best = candidates[np.argmin(np.hypot(*(ends[candidates, :2] - target).T))]
            node = tree.add(near, ends[best], controls[best], settings.duration)
            distance = float(np.hypot(*(ends[best, :2] - goal)))
            closest = min(closest, distance)
            if distance <= settings.goal_radius:
                reached = closing(tree, node)
        elapsed = time.perf_counter() - clock
        if progress is not None and elapsed - reported >= PROGRESS_SECONDS:
            reported = elapsed
            progress(settings.budget_used(iterations, elapsed), closest)
    if progress is not None:
        progress(1.0 if reached < 0 else settings.budget_used(iterations, elapsed), closest)
    return _result(tree, reached, settings, iterations, time.perf_counter() - clock, closest,
                   closing)


class _Closing:
    """The end of a plan into a goal inside the margin: from a state in the goal region,
    straight to the end of the goal's leg and along the leg (nothing for a free goal).

    ``controls`` counts the motions of the last drive to the leg's end, ``leg_controls``
    those along the leg, ``blocked`` the states whose drive was not free.
    """

    def __init__(self, free: World2D, model: DiffDrive, goal_leg: FloatArray) -> None:
        self.free, self.model, self.goal_leg = free, model, goal_leg
        self.controls = self.leg_controls = self.blocked = 0

    def __call__(self, tree: ControlTree, node: int) -> int:
        """Add the end of the plan after vertex ``node``; the last vertex, or -1 when the
        drive to the leg's end is not free."""
        if len(self.goal_leg) == 1:
            return node
        begin = tree.states[node]
        drive = np.array([[begin[:2], self.goal_leg[0]]])
        if not self.free.segments_free(drive)[0]:
            self.blocked += 1
            return -1
        to_leg = leg_motions(self.model, float(begin[2]), drive[0])
        along = leg_motions(self.model, float(to_leg[-1][0][2]), self.goal_leg)
        self.controls, self.leg_controls = len(to_leg), len(along)
        for state, control, duration in (*to_leg, *along):
            node = tree.add(node, state, control, duration)
        return node


def _result(tree: ControlTree, reached: int, settings: KinoSettings, iterations: int,
            seconds: float, closest: float, closing: _Closing) -> KinoResult:
    whole = tree.arrays()
    blocked = (f"; {closing.blocked} states in the goal region could not drive to its "
               "centre" if closing.blocked else "")
    if reached < 0:
        return KinoResult(NAME, False, np.zeros((0, 3)), np.zeros((0, 2)), np.zeros(0),
                          *whole, iterations, seconds, None, settings.seed,
                          f"goal region not reached in {iterations} iterations "
                          f"({seconds:.3g} s); the closest state is {closest:.3g} m from the "
                          f"goal{blocked}")
    rows = tree.branch(reached)
    return KinoResult(NAME, True, tree.states[rows], tree.controls[rows[1:]],
                      tree.durations[rows[1:]], *whole, iterations, seconds, seconds,
                      settings.seed, f"goal region reached in {iterations} iterations "
                      f"({seconds:.3g} s), {len(rows) - 1} controls{blocked}",
                      closing_controls=closing.controls,
                      goal_leg_controls=closing.leg_controls)


# ------------------------------------------------------------------------ outputs
def wheel_tracks(result: KinoResult, model: DiffDrive, tolerance: float = CHORD_TOLERANCE
                 ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """The centre and wheel paths along the plan's integrated motion.

    Every chord of the three polylines deviates from the true curve by at most
    ``tolerance`` metres.

    Returns:
        ``(centre (n, 2), left (n, 2), right (n, 2), t (n,))``: positions in metres at
        times ``t`` in seconds from the start; empty when the plan is not solved.
    """
    if len(result.states) == 0:
        return np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0)
    pieces, times = [result.states[:1]], [np.zeros(1)]
    starts = np.concatenate([[0.0], np.cumsum(result.durations)])
    for state, control, duration, t0 in zip(result.states[:-1], result.controls,
                                            result.durations, starts[:-1], strict=True):
        samples = track(state, control, duration, tolerance, reach=0.5 * model.wheel_base)
        steps = len(samples) - 1
        pieces.append(samples[1:])
        times.append(t0 + duration * (np.arange(1, steps + 1) / steps))
    states = np.concatenate(pieces)
    left, right = model.wheel_positions(states)
    return states[:, :2], left, right, np.concatenate(times)


def control_profile(result: KinoResult, model: DiffDrive
                    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """The plan's controls against time, as piecewise-constant profiles.

    Each control gives two samples, at the start and at the end of the interval it is
    held, so plotting ``t`` against a value draws the steps.

    Returns:
        ``(t, v, omega, left_speed, right_speed)``, each (2 (K - 1),): seconds, m/s,
        rad/s, m/s, m/s.
    """
    ends = np.cumsum(result.durations)
    t = np.column_stack([ends - result.durations, ends]).ravel()
    controls = np.repeat(result.controls, 2, axis=0)
    left, right = model.wheel_speeds(controls)
    return t, controls[:, 0], controls[:, 1], left, right
