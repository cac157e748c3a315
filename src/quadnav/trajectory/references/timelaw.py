"""A smooth time law for shapes flown round and round: :class:`PhaseLaw`.

A shape ``p(phi)`` (:mod:`quadnav.trajectory.references.builtin`) is flown by letting its phase
``phi`` run from 0 to ``total``. The phase's rate rises from 0 to the cruise ``rate`` over
``ramp`` seconds, cruises, and falls back to 0 over the last ``ramp`` seconds. The rise is
the C2 smoothstep ``s(u) = 10 u^3 - 15 u^4 + 6 u^5`` of ``u = t / ramp`` (the fall its
mirror), so the rate and its first two derivatives are continuous: a shape's position,
velocity and acceleration (``p'(phi) phidot`` and ``p''(phi) phidot^2 + p'(phi) phiddot``)
start and end at rest with no jump, and so does the jerk.

Each ramp covers half the phase it would at the cruise rate (``rate * ramp / 2``), so the
motion lasts ``total / rate + ramp`` s, and needs ``total >= rate * ramp``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray


def smoothstep(u: FloatArray) -> FloatArray:
    """``10 u^3 - 15 u^4 + 6 u^5`` for ``u`` in [0, 1]: 0 to 1 with zero first and second
    derivatives at both ends."""
    return u**3 * (10.0 - 15.0 * u + 6.0 * u**2)


def smoothstep_slope(u: FloatArray) -> FloatArray:
    """The derivative of :func:`smoothstep`, ``30 u^2 (1 - u)^2``."""
    return 30.0 * u**2 * (1.0 - u) ** 2


def smoothstep_area(u: FloatArray) -> FloatArray:
    """The integral of :func:`smoothstep` from 0 to ``u``, ``u^4 (5/2 - 3 u + u^2)``
    (1/2 at ``u = 1``)."""
    return u**4 * (2.5 - 3.0 * u + u**2)


@dataclass(frozen=True)
class PhaseLaw:
    """The phase over time of a motion that speeds up from rest, cruises and slows to rest
    (see the module docstring).

    Attributes:
        total: phase covered from start to end, > 0 (rad for the shapes here).
        rate: cruise rate of the phase, per s, > 0.
        ramp: time to speed up, and to slow down, s, > 0; at most ``total / rate``.
    """

    total: float
    rate: float
    ramp: float

    def __post_init__(self) -> None:
        if not (self.total > 0 and self.rate > 0 and self.ramp > 0):
            raise ValueError(f"total, rate and ramp must be > 0, got {self}")
        if self.total < self.rate * self.ramp * (1 - 1e-12):
            raise ValueError(f"the ramps need a phase of at least rate x ramp = "
                             f"{self.rate * self.ramp:g}, got {self.total:g}")

    @property
    def duration(self) -> float:
        """How long the motion lasts, s."""
        return self.total / self.rate + self.ramp

    def __call__(self, t: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The phase, its rate (per s) and its second derivative (per s^2) at ``t`` s, each
        shaped as ``t``; before 0 and after the end the phase holds still (0 or
        ``total``, rates 0)."""
        end, ramp, rate = self.duration, self.ramp, self.rate
        times = np.clip(np.asarray(t, dtype=np.float64), 0.0, end)
        rising = np.clip(times / ramp, 0.0, 1.0)  # 1 once cruising
        falling = np.clip((end - times) / ramp, 0.0, 1.0)  # below 1 only while slowing
        phase = rate * (ramp * smoothstep_area(rising)
                        + np.clip(times - ramp, 0.0, max(end - 2 * ramp, 0.0))
                        + ramp * (0.5 - smoothstep_area(falling)))
        phase_rate = rate * smoothstep(rising) * smoothstep(falling)
        phase_acceleration = rate / ramp * (smoothstep_slope(rising) - smoothstep_slope(falling))
        return phase, phase_rate, phase_acceleration
