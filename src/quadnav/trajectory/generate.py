"""From waypoints to a trajectory: pick a generator, allocate segment times, keep it free.

:func:`make_trajectory` is the stage's one entry point: the chosen generator, segment
times by the chosen timing (by default the near time-optimal one of
:mod:`quadnav.trajectory.timing.retime`: cruise at the top speed, slow only for turns and the
ends), safe corridors for the constrained minimum-snap QP, and — given a
:class:`SafeSpace` — straight legs out of the margin and collision-aware refinement of the
rest, which adds waypoints until a dense exact check finds it clear of the margin.

What the limits mean, for every method and timing: the speed (size of the velocity) never
exceeds ``v_max`` and the size of the acceleration vector never exceeds ``a_max`` — one
budget for speeding up, braking and turning — on dense samples of the trajectory.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.interpolate import PPoly

from quadnav.arrays import FloatArray
from quadnav.config import require
from quadnav.errors import QuadnavError
from quadnav.limits import ACCELERATION, SPEED, Range
from quadnav.planning.result import distinct
from quadnav.plugins import Registry
from quadnav.trajectory.clearance.collision import refine_until_free
from quadnav.trajectory.clearance.corridor import safe_corridors
from quadnav.trajectory.clearance.space import SafeSpace
from quadnav.trajectory.feasibility import Limits
from quadnav.trajectory.model import Trajectory, YawMode
from quadnav.trajectory.polynomials.cubic import cubic_spline
from quadnav.trajectory.polynomials.minsnap import minimum_snap
from quadnav.trajectory.polynomials.minsnap_qp import minimum_snap_qp
from quadnav.trajectory.polynomials.quintic import quintic_average, quintic_c2, quintic_segments
from quadnav.trajectory.timing.retime import Build, fastest_times, knots, stretch_where_fast
from quadnav.trajectory.timing.segment_times import (
    DEFAULT_A_MAX,
    DEFAULT_V_MAX,
    average_times,
    optimize_times,
    trapezoidal_times,
)
from quadnav.world.model import World

#: ``method(waypoints (N, 3) m, segment times (N - 1,) s, settings) -> Trajectory``: a
#: shape through every waypoint at the given times, at rest at both ends (the settings
#: give the limits, e.g. the quintic's cruise speed). ``examples/custom_trajectory.py``
#: is a template.
Method = Callable[[FloatArray, FloatArray, "TrajectorySettings"], Trajectory]
#: Trajectory methods by name, in the order the command line lists them: the built-in
#: ones, then those registered (``METHODS.register(name, method)``) or declared by an
#: installed package's ``quadnav.trajectory_methods`` entry point.
METHODS: Registry[Method] = Registry("trajectory method", "quadnav.trajectory_methods", {
    "minsnap": lambda waypoints, times, settings: minimum_snap(waypoints, times),
    "quintic": lambda waypoints, times, settings: quintic_segments(waypoints, times,
                                                                   settings.v_max),
    "quintic-c2": lambda waypoints, times, settings: quintic_c2(waypoints, times),
    "cubic": lambda waypoints, times, settings: cubic_spline(waypoints, times),
    "quintic-average": lambda waypoints, times, settings: quintic_average(waypoints, times),
})
#: Timings by name: near time-optimal along the curve (:mod:`quadnav.trajectory.timing.retime`),
#: each segment a rest-to-rest trapezoid then all stretched alike, or minimum snap plus
#: a weight times the total time (``minsnap`` only). ``quintic-average`` has its own.
TIMINGS = ("fastest", "rest-to-rest", "snap-time")
#: Legs out of the margin fly at this fraction of the speed and acceleration limits: they
#: pass close to obstacles, and a short move at full acceleration turns the body fast.
LEG_SLOW_DOWN = 0.5
#: Samples of a trajectory searched for its peak speed and acceleration.
_PEAK_SAMPLES = 4000
#: Extra stretch, relative, beyond what the sampled peaks ask for.
_STRETCH_ALLOWANCE = 1e-3
#: Ranges of the collision checks' spacing, m, and of the refinement rounds.
_SPACING = Range(1e-4, 1.0, "m")
_ROUNDS = Range(0, 100, whole=True)
#: Ranges of the speed and acceleration limits: the flags' (:mod:`quadnav.limits`), down
#: to the legs' share of them.
_SPEED = Range(LEG_SLOW_DOWN * SPEED.low, SPEED.high, SPEED.unit)
_ACCELERATION = Range(LEG_SLOW_DOWN * ACCELERATION.low, ACCELERATION.high, ACCELERATION.unit)


@dataclass(frozen=True)
class TrajectorySettings:
    """How to turn waypoints into a trajectory.

    Attributes:
        method: one of :data:`METHODS`.
        v_max: top speed, m/s (:data:`~quadnav.limits.SPEED`): the speed never exceeds
            it, and the ``fastest`` timing cruises at it wherever turns allow.
        a_max: largest size of the acceleration vector, m/s^2
            (:data:`~quadnav.limits.ACCELERATION`), for speeding up, braking and turning.
        timing: one of :data:`TIMINGS` (ignored by ``quintic-average``, whose segment
            times are length / ``v_max``, then stretched alike into the limits).
        corridor: minimum snap as a QP kept inside safe corridors around the path
            (``minsnap`` only).
        time_weight: weight of the total time against the snap cost, m^2/s^8
            (``snap-time`` timing).
        vehicle: what the vehicle can fly; when given, the ``fastest`` timing also slows
            where the roll and pitch rate would exceed its ``body_rate_max``.
        yaw: constant yaw, or facing the direction of travel.
        spacing: largest distance between positions checked for collisions, m.
        max_rounds: rounds of adding waypoints before giving up on a collision.
    """

    method: str = "minsnap"
    v_max: float = DEFAULT_V_MAX
    a_max: float = DEFAULT_A_MAX
    timing: str = "fastest"
    corridor: bool = False
    time_weight: float = 10.0
    vehicle: Limits | None = None
    yaw: YawMode = YawMode.CONSTANT
    spacing: float = 0.02
    max_rounds: int = 10

    def __post_init__(self) -> None:
        _SPEED.check(self.v_max, "v_max")
        _ACCELERATION.check(self.a_max, "a_max")
        _SPACING.check(self.spacing, "check spacing")
        _ROUNDS.check(self.max_rounds, "max rounds")
        checks = [
            (self.method in METHODS,
             f"unknown trajectory method {self.method!r}; expected one of "
             f"{', '.join(METHODS.names())}"),
            (self.timing in TIMINGS,
             f"unknown timing {self.timing!r}; expected one of {', '.join(TIMINGS)}"),
            (not (self.corridor or self.timing == "snap-time") or self.method == "minsnap",
             f"corridors and the snap-time timing need method minsnap, not {self.method!r}"),
            (math.isfinite(self.time_weight) and self.time_weight > 0,
             f"time weight must be > 0, got {self.time_weight}"),
        ]
        require(checks)

    def replace(self, **changes: object) -> TrajectorySettings:
        """A copy with some fields changed (see :func:`dataclasses.replace`)."""
        return dataclasses.replace(self, **changes)


def _generator(settings: TrajectorySettings, free_world: World | None) -> Build:
    if not settings.corridor:
        method = METHODS.get(settings.method)
        return lambda waypoints, times: method(waypoints, times, settings)
    if free_world is None:
        raise QuadnavError("corridors need a map to keep the trajectory in")

    def in_corridors(waypoints: FloatArray, times: FloatArray) -> Trajectory:
        corridor_waypoints, boxes = safe_corridors(free_world, waypoints)
        if len(corridor_waypoints) != len(waypoints):  # refinement splits free boxes only
            raise QuadnavError("safe corridors split a segment after the first allocation")
        return minimum_snap_qp(waypoints, times, corridors=boxes)

    return in_corridors


def make_trajectory(waypoints: ArrayLike, settings: TrajectorySettings | None = None,
                    space: SafeSpace | None = None) -> Trajectory:
    """A trajectory through ``waypoints`` (N, 3), metres, passing each one exactly, at
    rest at both ends, within the speed and acceleration limits of ``settings``.

    Args:
        waypoints: e.g. a planner's path; consecutive repeats are dropped.
        settings: method, limits and options (defaults: minimum snap, Tello-class limits).
        space: the map and the margin to keep. When given, the path's legs out of the
            margin (see :class:`SafeSpace`) are flown straight, each segment from rest to
            rest at :data:`LEG_SLOW_DOWN` of the limits (:func:`leg_pieces`), so they stay
            exactly on the path;
            the rest is one smooth piece to which
            waypoints are added until a dense exact check finds it free in the inflated
            map (see :func:`quadnav.trajectory.clearance.collision.refine_until_free`), and
            corridors can be used. Without it nothing is checked.
    """
    settings = settings or TrajectorySettings()
    points = distinct(waypoints)
    if len(points) < 2:
        raise QuadnavError(f"a trajectory needs at least 2 distinct waypoints, got {len(points)}")
    if space is None:
        return _piece(points, settings, None).replace(yaw_mode=settings.yaw)
    head, tail = space.split(points)
    main = [_piece(points[head:tail + 1], settings, space.inflated)] if tail > head else []
    return join_legs(leg_pieces(points[:head + 1], settings), main,
                     leg_pieces(points[tail:], settings), settings)


def leg_pieces(leg: FloatArray, settings: TrajectorySettings) -> list[Trajectory]:
    """The trajectories (one per segment of the polyline ``leg`` (K, 3)) that fly a leg
    out of the margin: each segment straight from rest to rest (with the ``fastest``
    timing's waypoints added on it, so it stays on the segment), at :data:`LEG_SLOW_DOWN`
    of the limits of ``settings``."""
    straight = settings.replace(corridor=False, timing="fastest",  # collinear points: a line
                                v_max=LEG_SLOW_DOWN * settings.v_max,
                                a_max=LEG_SLOW_DOWN * settings.a_max)
    return [_piece(leg[i:i + 2], straight, None) for i in range(len(leg) - 1)]


def join_legs(first: list[Trajectory], main: list[Trajectory], last: list[Trajectory],
              settings: TrajectorySettings) -> Trajectory:
    """One trajectory flying the start leg's pieces ``first`` (one per leg segment, see
    :func:`leg_pieces`), then ``main`` (at most one piece), then the goal leg's ``last``,
    with the main piece's solver facts and the yaw of ``settings``; ``leg_segments``
    counts the legs' segments."""
    pieces = [*first, *main, *last]
    joined = concatenate(pieces, settings.method, (main or pieces)[0].info)
    return joined.replace(yaw_mode=settings.yaw, leg_segments=(_segments(first),
                                                                 _segments(last)))


def _segments(pieces: list[Trajectory]) -> int:
    """How many segments ``pieces`` have together."""
    return sum(len(piece.segment_times) for piece in pieces)


def _piece(points: FloatArray, settings: TrajectorySettings, free_world: World | None
           ) -> Trajectory:
    """One trajectory from rest to rest through ``points`` (N, 3), kept in the free space
    of ``free_world`` when given, within the limits of ``settings``."""
    v, a = settings.v_max, settings.a_max
    fastest = settings.timing == "fastest" and settings.method != "quintic-average"
    if fastest:
        points = knots(points, v, a)
    if settings.corridor and free_world is not None:
        points, _ = safe_corridors(free_world, points)
    build = _generator(settings, free_world)

    def fly(waypoints: FloatArray, segment_times: FloatArray) -> Trajectory:
        if free_world is None:
            return build(waypoints, segment_times)
        return refine_until_free(free_world, waypoints, segment_times, build,
                                 max_rounds=settings.max_rounds, spacing=settings.spacing)

    trajectory = fly(points, _segment_times(points, settings, build, fastest))
    if fastest:
        return stretch_where_fast(trajectory, fly, v, a, settings.vehicle)
    stretch = slow_down_factor(trajectory, v, a)
    if stretch > 1.0:
        trajectory = fly(trajectory.waypoints, stretch * trajectory.segment_times)
    return trajectory.replace(info={**trajectory.info, "time_stretch": stretch})


def _segment_times(points: FloatArray, settings: TrajectorySettings, build: Build,
                   fastest: bool) -> FloatArray:
    """Segment times (N - 1,), s, for ``points`` (N, 3) by the timing of ``settings``
    (``fastest`` says whether that is the near time-optimal one)."""
    if settings.method == "quintic-average":
        return average_times(points, settings.v_max)
    times = trapezoidal_times(points, settings.v_max, settings.a_max)
    if fastest:
        return fastest_times(points, times, build, settings.v_max, settings.a_max)
    if settings.timing == "snap-time":
        return optimize_times(times, lambda t: minimum_snap(points, t).info["cost"],
                              settings.time_weight)
    return times


def concatenate(pieces: list[Trajectory], method: str, info: dict) -> Trajectory:
    """One trajectory flying ``pieces`` one after the other (each ends where the next
    begins), named ``method`` with ``info``."""
    if len(pieces) == 1:
        return pieces[0].replace(info=info)
    order = max(p.poly.c.shape[0] for p in pieces)
    coefficients = np.concatenate([np.pad(p.poly.c, ((order - p.poly.c.shape[0], 0),
                                                     (0, 0), (0, 0))) for p in pieces], axis=1)
    starts = np.cumsum([0.0, *(p.duration for p in pieces[:-1])])
    breaks = np.concatenate([[0.0], *(p.breaks[1:] + s for p, s in zip(pieces, starts,
                                                                        strict=True))])
    waypoints = np.concatenate([pieces[0].waypoints[:1], *(p.waypoints[1:] for p in pieces)])
    return Trajectory(PPoly(coefficients, breaks), waypoints, method, info=info)


def slow_down_factor(trajectory: Trajectory, v_max: float, a_max: float) -> float:
    """How much to stretch every segment time so the peak speed and acceleration, sampled
    at :data:`_PEAK_SAMPLES` points, come within ``v_max`` m/s and ``a_max`` m/s^2 (>= 1).

    Stretching time by k divides speeds by k and accelerations by k^2; the result is
    raised by :data:`_STRETCH_ALLOWANCE` to cover peaks between samples.
    """
    t = np.linspace(0.0, trajectory.duration, _PEAK_SAMPLES)
    speed = float(np.linalg.norm(trajectory.velocity(t), axis=1).max())
    acceleration = float(np.linalg.norm(trajectory.acceleration(t), axis=1).max())
    factor = max(speed / v_max, math.sqrt(acceleration / a_max))
    return factor * (1.0 + _STRETCH_ALLOWANCE) if factor > 1.0 else 1.0
