"""``rc`` mode's control law: a velocity from the trajectory and the estimate, as sticks.

The SDK's ``rc a b c d`` sets four sticks, each a whole number in -100..100, a percentage
of the full stick's speed :data:`RC_FULL_SPEED`: ``a`` right (+) / left, ``b`` forward
(+) / back, ``c`` up (+) / down, ``d`` yaw clockwise (+) seen from above. They act in the
drone's heading frame; the bridge never turns the drone, so that is the takeoff frame
(x forward, y left, z up — hence ``a`` is *minus* the y velocity).

The velocity asked for is the trajectory's plus a proportional correction towards the
trajectory's position, capped at the full stick's speed. Rounding to whole percent is
done with error diffusion (:class:`StickRounder`): what one command loses to rounding the
next one gets, so the sticks' average is the velocity asked for, to within 1 % of
:data:`RC_FULL_SPEED` over one period — unless the rounded sticks are not allowed (the
lost-link bound, :mod:`quadnav.hardware.bridge.lost_link`), when as few axes as need be are
rounded towards zero instead (or, failing all, the sticks are centred).
"""

from __future__ import annotations

from collections.abc import Callable
from itertools import combinations

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.hardware.bridge.frames import IntArray, body_to_map, map_to_body

#: Speed of a full stick (100), m/s (the Tello's default, slow, flight mode).
RC_FULL_SPEED = 1.0
#: Largest stick value.
STICK_MAX = 100
#: How many times the sticks are halved, at most, in search of allowed ones.
_HALVINGS = 6


def tracking_velocity(position_ref: ArrayLike, velocity_ref: ArrayLike,
                      position: ArrayLike, gain: float,
                      limit: float = RC_FULL_SPEED) -> FloatArray:
    """``velocity_ref + gain (position_ref - position)``, each (3,) in m, m/s and 1/s,
    scaled down to a speed of at most ``limit`` m/s -> (3,) m/s."""
    velocity = np.asarray(velocity_ref, dtype=np.float64) + gain * (
        np.asarray(position_ref, dtype=np.float64) - np.asarray(position, dtype=np.float64))
    speed = float(np.linalg.norm(velocity))
    return velocity * (limit / speed) if speed > limit else velocity


def stick_values(velocity: ArrayLike, yaw: float) -> FloatArray:
    """A map-frame velocity (3,) m/s of a drone facing ``yaw`` rad as unrounded sticks
    (right, forward, up) in percent of :data:`RC_FULL_SPEED`."""
    forward, left, up = map_to_body(velocity, yaw)
    return 100.0 / RC_FULL_SPEED * np.array([-left, forward, up])


def stick_velocity(sticks: ArrayLike, yaw: float) -> FloatArray:
    """The map-frame velocity (3,) m/s that sticks (right, forward, up, ...) in percent ask
    of a drone facing ``yaw`` rad (the inverse of :func:`stick_values`)."""
    right, forward, up = np.asarray(sticks, dtype=np.float64)[:3] * (RC_FULL_SPEED / 100.0)
    return body_to_map([forward, -right, up], yaw)


class StickRounder:
    """Whole-percent sticks (right, forward, up) whose running sum follows the unrounded
    ones' (error diffusion); the yaw stick is always 0."""

    def __init__(self) -> None:
        self._owed = np.zeros(3)

    def __call__(self, values: ArrayLike,
                 allowed: Callable[[IntArray], bool] = lambda sticks: True
                 ) -> tuple[int, int, int, int]:
        """The sticks (a, b, c, d) of the next ``rc`` command for unrounded ``values``:
        rounded with the error carried over — on as many axes as ``allowed`` (sticks
        (3,)) lets, the others rounded towards zero instead — else all rounded towards
        zero from a half, a quarter, ... of ``values`` (whole percent turn the velocity a
        little, which near the edge of what is allowed may not be), else centred."""
        values = np.clip(np.asarray(values, dtype=np.float64), -STICK_MAX, STICK_MAX)
        wanted = values + self._owed
        rounded = np.clip(np.rint(wanted), -STICK_MAX, STICK_MAX)
        candidates = [np.where(np.isin(np.arange(3), axes), np.trunc(values), rounded)
                      for axes in _subsets_by_size(3)]
        candidates += [np.trunc(values / 2.0**k) for k in range(1, _HALVINGS + 1)]
        sent: IntArray = next((c.astype(np.int64) for c in candidates
                               if allowed(c.astype(np.int64))), np.zeros(3, dtype=np.int64))
        self._owed = np.clip(wanted - sent, -1.0, 1.0)
        right, forward, up = (int(v) for v in sent)
        return right, forward, up, 0


def _subsets_by_size(n: int) -> list[list[int]]:
    """Every subset of ``range(n)``, smallest first."""
    return [list(axes) for size in range(n + 1) for axes in combinations(range(n), size)]
