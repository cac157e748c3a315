"""How a flight is simulated: :class:`SimSettings`."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from quadnav.arrays import FloatArray
from quadnav.config import frozen_vector, require, vector_field
from quadnav.limits import FORCE, GUSTS, RATE, SEED, SETTLE
from quadnav.sim.wind import wind_maker


@dataclass(frozen=True, eq=False)
class SimSettings:
    """Rates, stopping rule, success rule and disturbances of a simulated flight.

    Attributes:
        physics_rate: RK4 steps per second, Hz (:data:`~quadnav.limits.RATE`); a whole
            multiple of ``control_rate``.
        control_rate: controller updates per second, Hz (:data:`~quadnav.limits.RATE`).
        record_rate: samples kept in the flight record per second, Hz (at most the
            control rate; tracking metrics use every control step regardless).
        settle_time: time flown after the trajectory ends, s (:data:`~quadnav.limits.SETTLE`).
        goal_tolerance: largest final distance from the goal that counts as reached, m;
            also the highest the reference may be above the floor where the centre meets
            it for a take-off or a landing.
        touchdown_speed: fastest the centre may meet the floor where the reference is on
            it (within ``goal_tolerance``), m/s: a take-off or a landing. Meeting it
            faster, or where the reference is higher, is a crash that ends the flight
            (``hit the floor``). The default is the speed PX4 lands a multirotor at
            (its ``MPC_LAND_SPEED``).
        boundary_tolerance: how far the centre may stray outside the map's boundary
            before the flight counts as having left it, m (starts and goals may lie on
            the boundary itself).
        wind: (3,) constant external force, N, world frame (each in
            :data:`~quadnav.limits.FORCE`).
        wind_model: a wind model named by its spec (:mod:`quadnav.sim.wind`:
            ``module:Class(key=value, ...)`` or ``path/to/file.py:Class``), whose wind
            velocity, m/s, the drag acts on, asked once per control step; None for still
            air. Loaded and checked here (not built), so that a bad one is refused up
            front; each flight builds its own.
        gust_std: standard deviation of a random external force per axis, N
            (:data:`~quadnav.limits.GUSTS`), redrawn every ``gust_period`` s.
        gust_period: s.
        position_noise: standard deviation of measured position noise per axis, m.
        velocity_noise: m/s.
        attitude_noise: rad (a random small rotation per axis).
        gyro_noise: rad/s.
        seed: seed of the gusts and the noise; the same seed flies the same flight.
    """

    physics_rate: float = 1000.0
    control_rate: float = 1000.0
    record_rate: float = 100.0
    settle_time: float = 2.0
    goal_tolerance: float = 0.1
    touchdown_speed: float = 0.7
    boundary_tolerance: float = 0.05
    wind: FloatArray = vector_field(0.0, 0.0, 0.0)
    wind_model: str | None = None
    gust_std: float = 0.0
    gust_period: float = 0.2
    position_noise: float = 0.0
    velocity_noise: float = 0.0
    attitude_noise: float = 0.0
    gyro_noise: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "wind", frozen_vector(self.wind, 3))
        RATE.check(self.physics_rate, "physics rate")
        RATE.check(self.control_rate, "control rate")
        SETTLE.check(self.settle_time, "settle time")
        GUSTS.check(self.gust_std, "gust_std")
        SEED.check(self.seed, "seed")
        for force in self.wind:
            FORCE.check(float(force), "wind")
        if self.wind_model is not None:
            wind_maker(self.wind_model)
        ratio = self.physics_rate / self.control_rate
        nonnegative = ("boundary_tolerance", "position_noise", "velocity_noise",
                       "attitude_noise", "gyro_noise")
        require([
            (math.isfinite(self.record_rate) and self.record_rate > 0,
             "the record rate must be > 0 Hz"),
            (ratio >= 1 and abs(ratio - round(ratio)) < 1e-9,
             f"the physics rate ({self.physics_rate:g} Hz) must be a whole multiple of the "
             f"control rate ({self.control_rate:g} Hz)"),
            (self.record_rate <= self.control_rate,
             f"the record rate ({self.record_rate:g} Hz) must not exceed the control rate "
             f"({self.control_rate:g} Hz)"),
            (math.isfinite(self.goal_tolerance) and self.goal_tolerance > 0,
             f"goal tolerance must be > 0 m, got {self.goal_tolerance}"),
            (self.touchdown_speed > 0,
             f"touchdown speed must be > 0 m/s, got {self.touchdown_speed}"),
            (math.isfinite(self.gust_period) and self.gust_period > 0,
             f"gust period must be > 0 s, got {self.gust_period}"),
        ] + [(math.isfinite(getattr(self, k)) and getattr(self, k) >= 0,
              f"{k} must be >= 0, got {getattr(self, k)}") for k in nonnegative])

    def replace(self, **changes: object) -> SimSettings:
        """A copy with some fields changed (see :func:`dataclasses.replace`)."""
        return dataclasses.replace(self, **changes)

    @property
    def substeps(self) -> int:
        """Physics steps per control step."""
        return round(self.physics_rate / self.control_rate)

    @property
    def record_every(self) -> int:
        """Control steps per recorded sample."""
        return max(1, round(self.control_rate / self.record_rate))

    @property
    def noisy(self) -> bool:
        """Whether any measurement noise is on."""
        return (self.position_noise > 0 or self.velocity_noise > 0
                or self.attitude_noise > 0 or self.gyro_noise > 0)


def default_record_rate(control_rate: float) -> float:
    """The record rate for a ``control_rate`` Hz: the default, 100 Hz, or the control rate
    when it is lower (a record is kept at most every control step)."""
    return min(SimSettings.record_rate, control_rate)
