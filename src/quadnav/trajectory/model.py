"""The :class:`Trajectory` value: a piecewise polynomial in time per axis, with a yaw reference.

Underneath is one vector-valued :class:`scipy.interpolate.PPoly` (coefficients of shape
``(order + 1, segments, 3)``), so evaluation and derivatives of any order come from
scipy. Times are seconds from the start (``breaks[0] == 0``), positions metres in the
world frame (z up). Before the start and after the end the vehicle holds still: the
position is the first or last one and every derivative is zero.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from enum import Enum
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike
from scipy.interpolate import PPoly

from quadnav.arrays import FloatArray
from quadnav.trajectory.references.contract import Sampling

#: Below this horizontal speed, m/s, a travel-facing yaw follows the current segment's
#: direction instead of the velocity.
YAW_SPEED_FLOOR = 0.05
#: Names of the derivatives by order.
DERIVATIVES = ("position", "velocity", "acceleration", "jerk", "snap")


class YawMode(Enum):
    """How the yaw reference is made."""

    CONSTANT = "constant"
    TRAVEL = "travel"


def ppoly_from_ascending(coefficients: ArrayLike, breaks: ArrayLike) -> PPoly:
    """A vector-valued PPoly from per-segment coefficients in ascending powers of the
    local time ``t - breaks[i]``: ``coefficients`` (segments, order + 1, 3), breaks
    (segments + 1,) seconds."""
    c = np.asarray(coefficients, dtype=np.float64)
    return PPoly(np.ascontiguousarray(c.transpose(1, 0, 2)[::-1]), np.asarray(breaks, float))


@dataclass(frozen=True, eq=False)
class Trajectory(Sampling):
    """A smooth reference through waypoints (a
    :class:`~quadnav.trajectory.references.contract.Reference`).

    Attributes:
        poly: position as a vector-valued PPoly of time (s -> m, 3 axes); its breaks are
            the times at which the waypoints are passed, starting at 0.
        waypoints: (N, 3) points passed at the breaks, metres.
        method: how it was made, e.g. ``"minsnap"``, ``"quintic"`` or ``"cubic"``.
        yaw_mode: constant yaw, or facing the direction of travel.
        yaw0: the constant yaw (and the yaw when there is no horizontal motion), rad.
        info: solver facts for reports (e.g. snap cost, corridor count), JSON-ready.
        leg_segments: how many of the first and of the last waypoint intervals are the
            legs out of the safety margin at the start and into it at the goal (0 without
            such legs); between them the trajectory keeps the whole margin (see
            :mod:`quadnav.trajectory.clearance.space`).
    """

    poly: PPoly
    waypoints: FloatArray
    method: str
    yaw_mode: YawMode = YawMode.CONSTANT
    yaw0: float = 0.0
    info: dict = field(default_factory=dict)
    leg_segments: tuple[int, int] = (0, 0)

    def __post_init__(self) -> None:
        waypoints = np.array(self.waypoints, dtype=np.float64).reshape(-1, 3)
        if len(waypoints) != len(self.poly.x):
            raise ValueError(f"{len(waypoints)} waypoints for {len(self.poly.x)} breaks")
        if self.poly.x[0] != 0.0 or np.any(np.diff(self.poly.x) <= 0):
            raise ValueError("breaks must start at 0 s and increase")
        waypoints.flags.writeable = False
        object.__setattr__(self, "waypoints", waypoints)

    def replace(self, **changes: object) -> Trajectory:
        """A copy with some fields changed (see :func:`dataclasses.replace`)."""
        return dataclasses.replace(self, **changes)

    @property
    def breaks(self) -> FloatArray:
        """(N,) times, s, at which the waypoints are passed."""
        return self.poly.x

    @property
    def duration(self) -> float:
        """Total time, s."""
        return float(self.poly.x[-1])

    @property
    def main_window(self) -> tuple[float, float]:
        """``(begin, end)``, s: the times between the legs, when the whole margin is kept
        (breaks, so exactly the times the legs end and begin)."""
        first, last = self.leg_segments
        return float(self.breaks[first]), float(self.breaks[-1 - last])

    @property
    def legs(self) -> tuple[float, float]:
        """How long the leg out of the margin at the start and the leg into it at the goal
        take, s (0 without such legs)."""
        begin, end = self.main_window
        return begin, self.duration - end

    @property
    def segment_times(self) -> FloatArray:
        """(N - 1,) duration of each segment, s."""
        return np.diff(self.poly.x)

    @cached_property
    def _derivatives(self) -> list[PPoly]:
        polys = [self.poly]
        for _ in range(len(DERIVATIVES) - 1):
            polys.append(polys[-1].derivative())
        return polys

    def derivative(self, t: ArrayLike, order: int = 0) -> FloatArray:
        """The ``order``-th time derivative at ``t`` (scalar -> (3,), (N,) -> (N, 3)).

        Units m/s^order. Outside [0, duration] the vehicle holds still.
        """
        if not 0 <= order < len(DERIVATIVES):
            raise ValueError(f"order must be 0..{len(DERIVATIVES) - 1}, got {order}")
        times = np.asarray(t, dtype=np.float64)
        clipped = np.clip(times, 0.0, self.duration)
        values = self._derivatives[order](clipped)
        if order > 0:
            values = np.where((times == clipped)[..., None], values, 0.0)
        return values

    def position(self, t: ArrayLike) -> FloatArray:
        """Position, m, at ``t`` s."""
        return self.derivative(t, 0)

    def velocity(self, t: ArrayLike) -> FloatArray:
        """Velocity, m/s, at ``t`` s."""
        return self.derivative(t, 1)

    def acceleration(self, t: ArrayLike) -> FloatArray:
        """Acceleration, m/s^2, at ``t`` s."""
        return self.derivative(t, 2)

    def jerk(self, t: ArrayLike) -> FloatArray:
        """Jerk, m/s^3, at ``t`` s."""
        return self.derivative(t, 3)

    def snap(self, t: ArrayLike) -> FloatArray:
        """Snap, m/s^4, at ``t`` s."""
        return self.derivative(t, 4)

    def yaw(self, t: ArrayLike) -> FloatArray:
        """Yaw reference, rad, at ``t`` s (scalar -> scalar, (N,) -> (N,)).

        Constant mode: ``yaw0``. Travel mode: the heading of the horizontal velocity; when
        that is below :data:`YAW_SPEED_FLOOR`, the heading of the current segment's chord,
        and ``yaw0`` when that is vertical.
        """
        times = np.asarray(t, dtype=np.float64)
        if self.yaw_mode is YawMode.CONSTANT:
            return np.full(times.shape, self.yaw0) if times.ndim else np.float64(self.yaw0)
        velocity = self.velocity(times)
        segment = np.clip(np.searchsorted(self.breaks, times, side="right") - 1, 0,
                          len(self.breaks) - 2)
        chord = self.waypoints[segment + 1] - self.waypoints[segment]
        fast = np.hypot(velocity[..., 0], velocity[..., 1]) >= YAW_SPEED_FLOOR
        direction = np.where(fast[..., None], velocity[..., :2], chord[..., :2])
        flat = np.hypot(direction[..., 0], direction[..., 1]) == 0
        return np.where(flat, self.yaw0, np.arctan2(direction[..., 1], direction[..., 0]))


def hold_trajectory(position: ArrayLike, duration: float, yaw: float = 0.0) -> Trajectory:
    """Hover at ``position`` (3,) m heading ``yaw`` rad for ``duration`` s (method ``hold``)."""
    point = np.asarray(position, dtype=np.float64).reshape(3)
    return Trajectory(ppoly_from_ascending(point.reshape(1, 1, 3), [0.0, duration]),
                      np.stack([point, point]), "hold", yaw0=yaw)
