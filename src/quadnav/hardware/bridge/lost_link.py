"""``rc`` mode's bound for a lost link: sticks that a dead link cannot carry out of the fence.

A Tello keeps flying the last ``rc`` sticks it heard until it lands by itself,
:data:`~quadnav.hardware.sdk.AUTO_LAND_AFTER` (15) s after the last command it heard. If
the link dies, the drone therefore flies on at the last commanded velocity ``v`` for up
to 15 s, then brakes and descends straight down. That run is modelled as the straight
segment from the drone's position ``p``

    p -> p + v (HOLD + LAG) + v |v| / (2 BRAKE)

(:func:`run_length`): :data:`HOLD` s at ``v``, :data:`LAG` s more because the drone's
velocity follows its sticks with a delay, and the braking distance at a gentle
:data:`BRAKE` deceleration. Every stick command keeps that segment inside the geofence
(:meth:`LostLinkBound.is_safe`, quadnav's exact segment test), from the dead-reckoned
position — on a leg out of (or into) the margin, inside the leg's room
(:mod:`quadnav.hardware.bridge.leg_room`: no closer to a block than the start or goal itself, nor
to a wall than the leg), where a drone on its leg may be. (The descent that follows is
straight down, onto the floor — or onto a block the drone is above.) The speed allowed
along a direction is :func:`safe_speed` of the distance to the fence along it
(:meth:`LostLinkBound.reach`): near walls, blocks, the floor's or the ceiling's margin
only slow sticks are safe — 15 s at 0.01 m/s (one stick percent) is already 0.15 m.

The trajectory's own pace is slowed to match (:meth:`LostLinkBound.pace`): the bridge
follows the same path, more slowly where the fence is near.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.hardware.bridge.geofence import Region
from quadnav.hardware.bridge.rc import RC_FULL_SPEED, STICK_MAX
from quadnav.hardware.sdk import AUTO_LAND_AFTER
from quadnav.trajectory.model import Trajectory

#: Drone seconds a lost link leaves the last sticks in force (the firmware's auto-land).
HOLD = AUTO_LAND_AFTER
#: Drone seconds the velocity lags behind the sticks, counted on top of :data:`HOLD`.
LAG = 0.5
#: Deceleration of the braking at the end of the run, m/s^2 (gentle: the Tello brakes
#: harder).
BRAKE = 1.0
#: Speeds below this, m/s, count as not moving (a hundredth of a stick percent).
STILL = 1e-4
#: How much shorter than the true distance to the fence :meth:`LostLinkBound.reach` may
#: be, m.
REACH_TOLERANCE = 1e-5
#: ``pace`` below this fraction of the trajectory's own speed counts as a stall.
STALL_PACE = 1e-3
#: The slowest a reference on a leg moves on, m/s: one stick percent (the sticks cannot
#: follow anything slower anyway).
LEG_CREEP = RC_FULL_SPEED / STICK_MAX


def run_length(speed: float) -> float:
    """Metres a drone flying at ``speed`` m/s covers before it stands still, if the link
    dies now (see the module's description)."""
    return speed * (HOLD + LAG) + speed * speed / (2.0 * BRAKE)


def safe_speed(distance: float) -> float:
    """The largest speed, m/s, whose :func:`run_length` is at most ``distance`` m."""
    if distance <= 0:
        return 0.0
    hold = HOLD + LAG
    return BRAKE * (math.sqrt(hold * hold + 2.0 * distance / BRAKE) - hold)


def _unit(vector: FloatArray) -> tuple[FloatArray, float]:
    """``vector`` (3,) as a unit vector and its length (a zero vector stays zero)."""
    length = float(np.linalg.norm(vector))
    return (vector / length if length > 0 else vector), length


@dataclass(frozen=True, eq=False)
class LostLinkBound:
    """The stick bound for one geofence, or one leg's room (see the module's description);
    ``fence`` is where the run must stay."""

    fence: Region

    @cached_property
    def _ray_length(self) -> float:
        """A length no straight run inside the fence exceeds: its boundary's diagonal, m."""
        return float(np.linalg.norm(self.fence.free_world.extent)) + 1.0

    def reach(self, position: ArrayLike, direction: ArrayLike,
              up_to: float | None = None) -> float:
        """Metres from ``position`` (3,) along the unit ``direction`` (3,) to the edge of
        the fence (0 from outside it), or ``up_to`` m if that is nearer: the longest
        straight move the fence's own exact segment test allows, found by bisection to
        within :data:`REACH_TOLERANCE` below."""
        p = np.asarray(position, dtype=np.float64)
        d = np.asarray(direction, dtype=np.float64)
        fence = self.fence
        low, high = 0.0, self._ray_length if up_to is None else up_to
        if not fence.point_ok(p):
            return 0.0
        if fence.segment_ok(p, p + high * d):
            return high
        while high - low > REACH_TOLERANCE:
            middle = 0.5 * (low + high)
            if fence.segment_ok(p, p + middle * d):
                low = middle
            else:
                high = middle
        return low

    def is_safe(self, position: ArrayLike, velocity: ArrayLike) -> bool:
        """Whether a link lost now, with ``velocity`` (3,) m/s commanded at ``position``
        (3,) m, leaves the drone's run inside the fence."""
        p = np.asarray(position, dtype=np.float64)
        direction, speed = _unit(np.asarray(velocity, dtype=np.float64))
        if speed < STILL:
            return self.fence.point_ok(p)
        return self.fence.segment_ok(p, p + run_length(speed) * direction)

    def pace(self, position: ArrayLike, velocity: ArrayLike) -> float:
        """The fraction, in [0, 1], of ``velocity`` (3,) m/s that is safe at ``position``
        (3,) m along the same direction: how fast the trajectory may be followed there."""
        direction, speed = _unit(np.asarray(velocity, dtype=np.float64))
        if speed < STILL or self.is_safe(position, velocity):
            return 1.0
        reach = self.reach(position, direction, up_to=run_length(speed))
        return min(1.0, safe_speed(reach) / speed)

    def limit(self, position: ArrayLike, velocity: ArrayLike) -> FloatArray:
        """The velocity (3,) m/s closest to ``velocity`` that this bound allows at
        ``position`` (3,) m, found part by part: the vertical part is limited by the room
        above or below, the horizontal part by the room along it, then the whole by the
        room along its direction (so a small correction towards the floor does not stop
        the horizontal motion) — or, when that gets further along ``velocity``, the same
        with the part along each of the map's axes (so a small correction towards the wall
        or block that a leg runs along does not stop the motion along it)."""
        p = np.asarray(position, dtype=np.float64)
        v = np.asarray(velocity, dtype=np.float64)
        candidates = []
        for parts in ([[0.0, 0.0, 1.0], [1.0, 1.0, 0.0]], np.eye(3)):
            limited = sum(v * part * self.pace(p, v * part) for part in np.asarray(parts))
            candidates.append(limited * self.pace(p, limited))
        return max(candidates, key=lambda c: float(np.dot(c, v)))


@dataclass(frozen=True)
class SlowedFlight:
    """The trajectory followed at the pace the lost-link bound allows, perfect tracking.

    Attributes:
        duration: drone seconds the slowed flight takes (inf: it stalls).
        planned: drone seconds the trajectory itself takes.
        slowest: the least pace met, in [0, 1].
        where: (3,) m, where the least pace was met.
    """

    duration: float
    planned: float
    slowest: float
    where: FloatArray

    @property
    def stalls(self) -> bool:
        """Whether the flight cannot be finished: somewhere no safe speed moves on."""
        return not math.isfinite(self.duration)


def creeping_pace(pace: float, speed: float) -> float:
    """``pace`` (in [0, 1]) of a reference on a leg that moves at ``speed`` m/s, raised so
    that it moves on at :data:`LEG_CREEP` at least (at its own speed when that is less).

    A leg may end on a wall, or as close to a block as its start: a stick bounded for a
    lost link can only creep towards such a point (it stops 15.5 cm short, where one stick
    percent is no longer safe), and the exact pace would stall the reference on its way
    there. The sticks themselves stay bounded exactly: the drone lags behind and, at the
    goal, lands short of it rather than come closer than the bound allows."""
    return 1.0 if speed <= 0 else max(pace, min(1.0, LEG_CREEP / speed))


def slowed_flight(pace_at: Callable[[float], float], trajectory: Trajectory,
                  rate: float) -> SlowedFlight:
    """Follow ``trajectory`` at ``rate`` steps per drone second, each step advancing the
    trajectory's time by the step times ``pace_at(time)``, the pace there (as the bridge
    does in ``rc`` mode: :meth:`LostLinkBound.pace` at the trajectory's position and
    velocity, for the fence or, on a leg, the leg's room)."""
    period, tau, elapsed = 1.0 / rate, 0.0, 0.0
    slowest, where = 1.0, trajectory.position(0.0)
    while tau < trajectory.duration:
        position = trajectory.position(tau)
        pace = pace_at(tau)
        if pace < slowest:
            slowest, where = pace, position
        if pace < STALL_PACE:
            return SlowedFlight(math.inf, trajectory.duration, pace, position)
        tau += pace * period
        elapsed += period
    return SlowedFlight(elapsed, trajectory.duration, slowest, where)
