"""A reference of your own, in one file: a rose curve flown as itself (exact derivatives,
no polynomial fit) by the same closed loop as every other flight.

A reference is any object with ``duration`` (s) and ``position(t)``, ``velocity(t)``,
``acceleration(t)`` ((N, 3) for N times, world frame, SI), ``yaw(t)`` ((N,) rad) and
``sample(dt)`` (inherit :class:`~quadnav.trajectory.references.contract.Sampling` for it), for
``simulate`` and ``track_reference``. Use this file as a template. (The command line flies
a plain class with ``update(t) -> flat outputs`` instead: examples/plain_trajectory.py.)

Run: python examples/custom_reference.py [MAP X Y Z]   (default: open space; with a map, the
rose is centred at (X, Y, Z) in it, and a touch of a block ends the flight)
"""

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from quadnav.sim.simulate import simulate
from quadnav.tracking import track_reference
from quadnav.trajectory.references.contract import Sampling
from quadnav.world import load_world


@dataclass(frozen=True)
class Rose(Sampling):
    """``r = radius cos(petals θ)`` in the horizontal plane through ``centre`` (m), θ = ω t,
    with the phase rate ramped smoothly from and to rest over ``ramp`` s."""

    radius: float = 1.0
    petals: int = 3
    period: float = 12.0
    centre: tuple = (0.0, 0.0, 1.0)
    ramp: float = 2.0

    @property
    def duration(self) -> float:
        return self.period + self.ramp

    def _phase(self, t):
        """θ (N,) and its first two derivatives: the rate rises as a smoothstep over the
        first ``ramp`` s and falls over the last, so θ goes from 0 to 2π."""
        t = np.clip(np.asarray(t, dtype=float).reshape(-1), 0.0, self.duration)
        rate = 2 * np.pi / self.period
        up, down = np.clip(t / self.ramp, 0, 1), np.clip((self.duration - t) / self.ramp, 0, 1)
        def step(s):
            return s * s * s * (10 - 15 * s + 6 * s * s)
        def integral(s):  # ∫ step ds
            return s ** 4 * (2.5 - 3 * s + s * s)
        def slope(s):
            return 30 * s * s * (1 - s) ** 2
        slowed = self.ramp * ((1 - down) - (integral(1) - integral(down)))  # lost braking
        theta = rate * (self.ramp * integral(up) + np.maximum(t - self.ramp, 0)
                        - np.where(t > self.period, slowed, 0))
        theta_dot = rate * step(up) * step(down)
        theta_ddot = rate * (slope(up) * step(down) - step(up) * slope(down)) / self.ramp
        return theta, theta_dot, theta_ddot

    def _shape(self, theta):
        """Position on the curve (N, 2) and its first two derivatives in θ."""
        k, a = self.petals, self.radius
        r, dr = a * np.cos(k * theta), -a * k * np.sin(k * theta)
        ddr = -k * k * r
        c, s = np.cos(theta), np.sin(theta)
        p = np.stack([r * c, r * s], axis=1)
        dp = np.stack([dr * c - r * s, dr * s + r * c], axis=1)
        ddp = np.stack([ddr * c - 2 * dr * s - r * c, ddr * s + 2 * dr * c - r * s], axis=1)
        return p, dp, ddp

    def _state(self, t):
        """Position, velocity and acceleration (N, 3) at the times ``t``."""
        theta, rate, rate_dot = self._phase(t)
        p, dp, ddp = self._shape(theta)
        flat = np.zeros((len(theta), 1))
        return (np.hstack([p, flat]) + self.centre, np.hstack([dp * rate[:, None], flat]),
                np.hstack([ddp * rate[:, None] ** 2 + dp * rate_dot[:, None], flat]))

    def position(self, t):
        return _as_given(t, self._state(t)[0])

    def velocity(self, t):
        return _as_given(t, self._state(t)[1])

    def acceleration(self, t):
        return _as_given(t, self._state(t)[2])

    def yaw(self, t):
        return _as_given(t, np.zeros(np.size(t)))


def _as_given(t, values):
    """``values`` for the times ``t``: one row for a scalar ``t``, all rows otherwise."""
    return values[0] if np.ndim(t) == 0 else values

if __name__ == "__main__":
    if len(sys.argv) > 1:  # in a map: the real blocks and boundary, exact contact checks
        world, centre = load_world(sys.argv[1]), tuple(map(float, sys.argv[2:5]))
        flight = simulate(Rose(centre=centre), world=world)
        where = f"in {Path(sys.argv[1]).name} round {centre}"
    else:
        flight, where = track_reference(Rose()).flight, "in open space"
    print(f"rose {where}: {flight.ending.value}, RMS tracking error "
          f"{100 * flight.rms_tracking_error:.2f} cm, max {100 * flight.max_tracking_error:.2f} cm")
