"""The quadrotor as a point mass steered by roll, pitch and thrust: :class:`SampledQuadrotor`.

State ``(x, y, z, vx, vy, vz)``: position (m) and velocity (m/s) in quadnav's world frame.
Control ``(phi, theta, T)``: roll and pitch (rad) and collective thrust (N); the yaw
``psi`` is a fixed model parameter. The attitude is assumed to follow its command at
once, so a control held for a while is a constant acceleration and the motion is exactly
a parabola: :meth:`SampledQuadrotor.propagate` needs no numerical integration.

Sign convention
---------------
quadnav's world frame is **z up** (x and y horizontal, gravity along -z). The body
attitude is ``R = Rz(psi) Ry(theta) Rx(phi)`` (ZYX Euler angles: yaw, then pitch, then
roll) and the thrust pushes along the body's +z axis, so::

    a = R e3 T/m - g e3
    a_x = ( cos(phi) sin(theta) cos(psi) + sin(phi) sin(psi)) T/m
    a_y = ( cos(phi) sin(theta) sin(psi) - sin(phi) cos(psi)) T/m
    a_z =   cos(phi) cos(theta) T/m - g

The issue's formula, ``a_x = (-cos phi sin theta cos psi - sin phi sin psi) T/m``,
``a_y = (-cos phi sin theta sin psi + sin phi cos psi) T/m``,
``a_z = g - cos phi cos theta T/m``, is the same model in a **z-down** (NED-like) frame
whose thrust pushes along the body's -z axis: ``a = g e3 - R e3 T/m`` with the same
``R``. Two equivalent ways to map it to quadnav:

* for the same numbers ``(phi, theta, psi, T)``, quadnav's acceleration is the issue's
  with every component's sign flipped: ``a = -a_issue``;
* as a change of frame (z-down forward-right-down to z-up forward-left-up, a half turn
  about x): positions map ``(x, y, z) -> (x, -y, -z)`` and angles
  ``(phi, theta, psi) -> (phi, -theta, -psi)``, so
  ``a(phi, theta, psi) = diag(1, -1, -1) a_issue(phi, -theta, -psi)``.

So in quadnav, at yaw 0: hovering is ``T = m g`` with ``phi = theta = 0``; a **positive
pitch accelerates towards +x**; a **positive roll accelerates towards -y**; more thrust
than ``m g`` climbs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.config import require


@dataclass(frozen=True)
class SampledQuadrotor:
    """Limits and constants of a point-mass quadrotor steered by (phi, theta, T).

    The defaults are a Tello-class drone (80 g): tilt up to 0.35 rad (20 degrees) in roll
    and pitch, thrust between 0.5 and 1.5 times its weight (so it can sink or climb at
    about g/2), yaw 0 and at most 2 m/s.

    Attributes:
        mass: kg, > 0.
        gravity: m/s^2, > 0.
        max_roll: roll limit, rad, in (0, pi/2): ``|phi| <= max_roll``.
        max_pitch: pitch limit, rad, in (0, pi/2): ``|theta| <= max_pitch``.
        min_thrust: N; ``None`` gives ``0.5 m g``.
        max_thrust: N, >= ``min_thrust``; ``None`` gives ``1.5 m g``.
        yaw: the fixed heading ``psi``, rad.
        speed_limit: m/s; planners prune states moving faster. ``None``: no limit.
    """

    mass: float = 0.08
    gravity: float = 9.81
    max_roll: float = 0.35
    max_pitch: float = 0.35
    min_thrust: float | None = None
    max_thrust: float | None = None
    yaw: float = 0.0
    speed_limit: float | None = 2.0

    def __post_init__(self) -> None:
        weight = self.mass * self.gravity
        if self.min_thrust is None:
            object.__setattr__(self, "min_thrust", 0.5 * weight)
        if self.max_thrust is None:
            object.__setattr__(self, "max_thrust", 1.5 * weight)
        checks = [
            (_positive(self.mass), f"mass must be > 0 kg, got {self.mass}"),
            (_positive(self.gravity), f"gravity must be > 0 m/s^2, got {self.gravity}"),
            (0 < self.max_roll < math.pi / 2,
             f"roll limit must be in (0, pi/2) rad, got {self.max_roll}"),
            (0 < self.max_pitch < math.pi / 2,
             f"pitch limit must be in (0, pi/2) rad, got {self.max_pitch}"),
            (math.isfinite(self.min_thrust) and 0 <= self.min_thrust <= self.max_thrust
             and math.isfinite(self.max_thrust) and self.max_thrust > 0,
             f"thrust range must satisfy 0 <= min <= max, max > 0 N, got "
             f"[{self.min_thrust}, {self.max_thrust}]"),
            (math.isfinite(self.yaw), f"yaw must be finite, got {self.yaw}"),
            (self.speed_limit is None or _positive(self.speed_limit),
             f"speed limit must be > 0 m/s, got {self.speed_limit}"),
        ]
        require(checks)

    @property
    def hover_thrust(self) -> float:
        """Thrust that holds the vehicle level and still, ``m g``, N."""
        return self.mass * self.gravity

    @property
    def control_lower(self) -> FloatArray:
        """(3,) lowest ``(phi, theta, T)``, rad, rad, N."""
        return np.array([-self.max_roll, -self.max_pitch, self.min_thrust])

    @property
    def control_upper(self) -> FloatArray:
        """(3,) highest ``(phi, theta, T)``, rad, rad, N."""
        return np.array([self.max_roll, self.max_pitch, self.max_thrust])

    @property
    def max_acceleration(self) -> float:
        """The largest ``|a|`` any control within the limits gives, m/s^2.

        ``|a|^2 = (T/m)^2 - 2 g (T/m) cos(phi) cos(theta) + g^2`` grows as the tilt grows
        and is convex in ``T``, so its maximum is at full tilt and an end of the thrust
        range.
        """
        tilt = math.cos(self.max_roll) * math.cos(self.max_pitch)
        g = self.gravity
        return max(math.sqrt(max(f * f - 2 * g * f * tilt + g * g, 0.0))
                   for f in (self.min_thrust / self.mass, self.max_thrust / self.mass))

    def acceleration(self, controls: ArrayLike) -> FloatArray:
        """World-frame acceleration (..., 3), m/s^2, of controls (..., 3) ``(phi, theta, T)``
        (z up; see the module docstring)."""
        u = np.asarray(controls, dtype=np.float64)
        phi, theta, specific = u[..., 0], u[..., 1], u[..., 2] / self.mass
        cpsi, spsi = math.cos(self.yaw), math.sin(self.yaw)
        cphi, sphi = np.cos(phi), np.sin(phi)
        tilt = cphi * np.sin(theta)
        return np.stack([(tilt * cpsi + sphi * spsi) * specific,
                         (tilt * spsi - sphi * cpsi) * specific,
                         cphi * np.cos(theta) * specific - self.gravity], axis=-1)

    def control_for(self, acceleration: ArrayLike) -> FloatArray | None:
        """The control (3,) ``(phi, theta, T)`` that gives ``acceleration`` (3,) m/s^2, or
        None when it lies outside the limits (the inverse of :meth:`acceleration`)."""
        specific = np.asarray(acceleration, dtype=np.float64) + np.array([0, 0, self.gravity])
        size = float(np.linalg.norm(specific))
        if size == 0.0:
            return None
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        # The thrust direction in the heading frame is (cos phi sin theta, -sin phi,
        # cos phi cos theta).
        x, y, z = (c * specific[0] + s * specific[1], -s * specific[0] + c * specific[1],
                   specific[2])
        control = np.array([math.asin(-y / size), math.atan2(x, z), self.mass * size])
        inside = np.all((control >= self.control_lower) & (control <= self.control_upper))
        return control if inside else None

    def sample_controls(self, rng: np.random.Generator, count: int) -> FloatArray:
        """``count`` controls (count, 3) drawn uniformly within the limits."""
        return rng.uniform(self.control_lower, self.control_upper, size=(count, 3))

    def propagate(self, states: ArrayLike, controls: ArrayLike, duration: ArrayLike
                  ) -> FloatArray:
        """Exact states after holding each control for ``duration`` s.

        Shapes broadcast: states (..., 6), controls (..., 3), duration scalar or (...,);
        e.g. one state (6,) with many controls (n, 3) gives (n, 6).
        """
        return exact_states(states, self.acceleration(controls), duration)

    def chord_pieces(self, duration: float, tolerance: float) -> int:
        """Equal pieces a motion of ``duration`` s is cut into so that every point of it is
        within ``tolerance`` m of the chord of its piece, for every control.

        On a piece of length ``h`` the motion minus its chord is
        ``a/2 (s - s0)(s - s0 - h)``, at most ``|a| h^2 / 8`` in size; with
        ``|a| <= max_acceleration`` that is at most ``tolerance`` when
        ``h <= sqrt(8 tolerance / max_acceleration)``.
        """
        return max(1, math.ceil(duration * math.sqrt(self.max_acceleration / (8 * tolerance))))


def _positive(value: float) -> bool:
    return math.isfinite(value) and value > 0


def exact_states(states: ArrayLike, accelerations: ArrayLike, duration: ArrayLike
                 ) -> FloatArray:
    """States (..., 6) after ``duration`` s of constant acceleration: ``p + v t + a t^2/2``,
    ``v + a t``. Shapes broadcast: states (..., 6), accelerations (..., 3) m/s^2,
    duration scalar or (...,) s."""
    x = np.asarray(states, dtype=np.float64)
    a = np.asarray(accelerations, dtype=np.float64)
    t = np.asarray(duration, dtype=np.float64)[..., None]
    p, v = x[..., :3], x[..., 3:]
    return np.concatenate(np.broadcast_arrays(p + v * t + 0.5 * a * t * t, v + a * t), axis=-1)


def exact_positions(states: ArrayLike, accelerations: ArrayLike, times: ArrayLike
                    ) -> FloatArray:
    """Positions (..., P, 3), m, at times (..., P) s along motions of constant acceleration
    from states (..., 6) under accelerations (..., 3) m/s^2 (leading shapes broadcast)."""
    x = np.asarray(states, dtype=np.float64)[..., None, :]
    a = np.asarray(accelerations, dtype=np.float64)[..., None, :]
    t = np.asarray(times, dtype=np.float64)[..., None]
    return x[..., :3] + x[..., 3:] * t + 0.5 * a * t * t
