"""Can a Tello-class quadrotor fly a trajectory? Peaks of speed, acceleration, jerk, thrust,
tilt, body rate and angular acceleration against :class:`Limits`, and the clearance left to
the obstacles.

The thrust a quadrotor needs, per unit mass, is ``f = a + g e_z + D v`` (``a`` the
acceleration, ``e_z`` up, ``D`` its linear drag per unit mass, ``v`` the velocity): its
size over ``g`` is the thrust-to-weight ratio it must produce, and its angle from ``e_z``
the tilt of the body. The body turns as ``f`` does: the roll and pitch rate is the rate of
the thrust direction, ``|b'| = |f' - b (b . f')| / |f|`` with ``b = f / |f|`` and
``f' = j + D a`` (``j`` the jerk), and its roll and pitch angular acceleration, which the
rotors' torque must give, is ``|b x b''| = |(f'' - b (b . f'')) - 2 (b . f') b'| / |f|``
with ``f'' = s + D j`` (``s`` the snap; differentiate ``f = |f| b`` twice). A trajectory
whose jerk jumps at a waypoint (a cubic's) asks for an impulse of angular acceleration
there, which samples of the snap do not see. Everything is sampled every ``dt`` s and at
every waypoint time, so a peak between samples can be missed by a little.

Flying a trajectory ``k`` times slower divides speeds by ``k``, accelerations by ``k^2``,
jerks by ``k^3`` and snaps by ``k^4``: :func:`slowest_feasible_scale` finds the least ``k``
that brings every quantity within the limits.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.trajectory.model import Trajectory
from quadnav.world.model import World

#: Gravitational acceleration, m/s^2.
GRAVITY = 9.81


@dataclass(frozen=True)
class Limits:
    """What a Tello-class (80 g) quadrotor can fly; conservative indoor values.

    The speed and acceleration limits are above the time allocation's defaults
    (:data:`~quadnav.trajectory.timing.segment_times.DEFAULT_V_MAX`, ``DEFAULT_A_MAX``)
    because a smooth polynomial peaks above the trapezoidal profile those times assume (a
    rest-to-rest quintic reaches 1.875 times its mean speed).

    Attributes:
        v_max: speed, m/s, > 0.
        a_max: acceleration (size of the vector), m/s^2, > 0.
        jerk_max: jerk (size), m/s^3, > 0, or ``None`` for no limit.
        thrust_to_weight_max: largest thrust over weight the motors give, > 0.
        tilt_max: largest tilt of the body from upright, rad, in (0, pi).
        thrust_to_weight_min: smallest thrust over weight the motors give, > 0, or
            ``None`` for no limit.
        body_rate_max: largest roll and pitch rate, rad/s, > 0, or ``None`` for no limit.
        angular_acceleration_max: largest roll and pitch angular acceleration, rad/s^2,
            > 0, or ``None`` for no limit.
        drag: (3,) linear drag per unit mass along x, y, z, 1/s, >= 0 (the thrust also
            pushes against it).
    """

    v_max: float = 2.0
    a_max: float = 4.0
    jerk_max: float | None = None
    thrust_to_weight_max: float = 2.0
    tilt_max: float = math.radians(35.0)
    thrust_to_weight_min: float | None = None
    body_rate_max: float | None = None
    angular_acceleration_max: float | None = None
    drag: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        for name, value in dataclasses.asdict(self).items():
            if name == "drag":
                if len(value) != 3 or not all(math.isfinite(d) and d >= 0 for d in value):
                    raise QuadnavError(f"limit drag must be 3 finite numbers >= 0, got {value}")
                continue
            if value is None and name in _OPTIONAL:
                continue
            if not (math.isfinite(value) and value > 0):
                raise QuadnavError(f"limit {name} must be a finite number > 0, got {value}")
        if self.tilt_max >= math.pi:
            raise QuadnavError(f"limit tilt_max must be below pi rad, got {self.tilt_max}")


@dataclass(frozen=True)
class Peak:
    """An extreme value of a sampled quantity and the time it occurs, s."""

    value: float
    t: float

    def as_dict(self) -> dict:
        """``{"value": ..., "t": ...}``."""
        return {"value": self.value, "t": self.t}


class _Quantity(NamedTuple):
    """How one peaked quantity is named, shown and limited."""

    field: str
    label: str
    unit: str
    shown: float  # display units per SI unit
    limit: str  # the Limits attribute
    largest: bool = True  # a maximum (else a minimum)


_QUANTITIES = (
    _Quantity("max_speed", "speed", " m/s", 1.0, "v_max"),
    _Quantity("max_acceleration", "acceleration", " m/s^2", 1.0, "a_max"),
    _Quantity("max_jerk", "jerk", " m/s^3", 1.0, "jerk_max"),
    _Quantity("max_thrust_to_weight", "thrust-to-weight ratio", "", 1.0,
              "thrust_to_weight_max"),
    _Quantity("min_thrust_to_weight", "thrust-to-weight ratio", "", 1.0,
              "thrust_to_weight_min", largest=False),
    _Quantity("max_tilt", "tilt", " deg", math.degrees(1.0), "tilt_max"),
    _Quantity("max_body_rate", "roll/pitch rate", " deg/s", math.degrees(1.0),
              "body_rate_max"),
    _Quantity("max_angular_acceleration", "roll/pitch acceleration", " rad/s^2", 1.0,
              "angular_acceleration_max"),
)
#: Limits that may be None (no limit).
_OPTIONAL = ("jerk_max", "thrust_to_weight_min", "body_rate_max", "angular_acceleration_max")


@dataclass(frozen=True, eq=False)
class FeasibilityReport:
    """Peaks of a sampled trajectory against :class:`Limits`.

    Attributes:
        dt: sample interval, s (waypoint times are sampled too).
        duration: length of the trajectory, s.
        max_speed: largest speed, m/s.
        max_acceleration: largest acceleration (size), m/s^2.
        max_jerk: largest jerk (size), m/s^3 (at a waypoint, the value just after it).
        max_thrust_to_weight: largest ``|f| / g`` (module docstring).
        min_thrust_to_weight: smallest ``|f| / g``.
        max_tilt: largest angle between ``f`` and ``e_z``, rad.
        max_body_rate: largest roll and pitch rate, rad/s.
        max_angular_acceleration: largest roll and pitch angular acceleration, rad/s^2.
        min_clearance: smallest clearance of the sampled positions in the world, m
            (negative inside an obstacle), or ``None`` when no world was given.
        limits: the limits checked.
        world_name: the world's name, or ``None``.
        violations: one line per exceeded limit, naming the quantity, value, limit and time.
        broken: the :class:`Limits` field of each exceeded limit, in the order of
            ``violations`` (a touched obstacle, the last violation, has none).
    """

    dt: float
    duration: float
    max_speed: Peak
    max_acceleration: Peak
    max_jerk: Peak
    max_thrust_to_weight: Peak
    min_thrust_to_weight: Peak
    max_tilt: Peak
    max_body_rate: Peak
    max_angular_acceleration: Peak
    min_clearance: Peak | None
    limits: Limits
    world_name: str | None
    violations: tuple[str, ...]
    broken: tuple[str, ...]

    @property
    def ok(self) -> bool:
        """Whether no limit is exceeded and no sample touches an obstacle."""
        return not self.violations

    def as_dict(self) -> dict:
        """A JSON-ready dict: SI units, the tilts in radians."""
        peaks = {q.field: getattr(self, q.field).as_dict() for q in _QUANTITIES}
        clearance = None if self.min_clearance is None else self.min_clearance.as_dict()
        return {"ok": self.ok, "dt": self.dt, "duration": self.duration, **peaks,
                "min_clearance": clearance, "world": self.world_name,
                "limits": dataclasses.asdict(self.limits), "violations": list(self.violations)}

    def summary(self) -> str:
        """A few lines for people: each peak with its time and limit (tilt in degrees)."""
        count = len(self.violations)
        lines = ["feasible" if self.ok else f"NOT feasible: {count} violation{'s' * (count > 1)}"]
        for q in _QUANTITIES:
            peak, limit = getattr(self, q.field), getattr(self.limits, q.limit)
            bound = "no limit" if limit is None else f"limit {limit * q.shown:.3g}{q.unit}"
            lines.append(f"  {q.field[:3]} {q.label} {peak.value * q.shown:.3g}{q.unit} at "
                         f"{peak.t:.2f} s ({bound})")
        if self.min_clearance is not None:
            lines.append(f"  min clearance {self.min_clearance.value:.3g} m at "
                         f"{self.min_clearance.t:.2f} s in {self.world_name}")
        lines.extend(f"  violation: {line}" for line in self.violations)
        return "\n".join(lines)


def _peak(values: FloatArray, t: FloatArray, largest: bool = True) -> Peak:
    i = int(np.argmax(values) if largest else np.argmin(values))
    return Peak(float(values[i]), float(t[i]))


def feasibility(trajectory: Trajectory, free_world: World | None, limits: Limits | None = None,
                dt: float = 0.01) -> FeasibilityReport:
    """Check ``trajectory`` against ``limits`` and, given a world, its obstacles.

    Args:
        trajectory: the trajectory to check.
        free_world: the world whose free space the trajectory must stay in (e.g. inflated
            by the safety margin; a sample with clearance <= 0 is a violation), or ``None``.
        limits: the vehicle's limits (default: :class:`Limits`).
        dt: sample interval, s, > 0; the waypoint times are sampled as well.
    """
    if not (math.isfinite(dt) and dt > 0):
        raise QuadnavError(f"sample interval dt must be a finite number > 0 s, got {dt}")
    limits = limits or Limits()
    t, *motion = _motion(trajectory, dt)
    series = quantities(*motion, limits)
    peaks = {q.field: _peak(series[q.field], t, q.largest) for q in _QUANTITIES}
    violations, broken = [], []
    for q in _QUANTITIES:
        peak, limit = peaks[q.field], getattr(limits, q.limit)
        if _breaks(q, peak.value, limits):
            bound = "exceeds the limit" if q.largest else "is below the least"
            value, shown_limit = _apart(peak.value * q.shown, limit * q.shown)
            violations.append(f"{q.label} {value}{q.unit} {bound} {shown_limit}{q.unit} at "
                              f"t = {peak.t:.2f} s")
            broken.append(q.limit)
    clearance = None
    if free_world is not None:
        clearance = _peak(free_world.clearances(trajectory.position(t)), t, largest=False)
        if clearance.value <= 0:
            violations.append(f"clearance {clearance.value:.3g} m is not above 0 m at "
                              f"t = {clearance.t:.2f} s: the trajectory touches or enters "
                              f"an obstacle of {free_world.name}")
    return FeasibilityReport(dt=float(dt), duration=trajectory.duration, **peaks,
                             min_clearance=clearance, limits=limits,
                             world_name=None if free_world is None else free_world.name,
                             violations=tuple(violations), broken=tuple(broken))


def _apart(value: float, limit: float) -> tuple[str, str]:
    """``value`` and ``limit`` written with 3 significant digits, or with as many more (up
    to 6) as it takes to tell them apart."""
    for digits in range(3, 7):
        shown = f"{value:.{digits}g}", f"{limit:.{digits}g}"
        if shown[0] != shown[1]:
            break
    return shown


def _motion(trajectory: Trajectory, dt: float
            ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """Times (N,) s every ``dt`` s and at every waypoint, and the velocity, acceleration,
    jerk and snap (N, 3) there."""
    t = np.union1d(trajectory.sample(dt).t, trajectory.breaks)
    return t, *(trajectory.derivative(t, order) for order in (1, 2, 3, 4))


def _breaks(q: _Quantity, worst: float, limits: Limits) -> bool:
    """Whether ``worst``, the peak of quantity ``q``, is beyond its limit in ``limits``."""
    limit = getattr(limits, q.limit)
    return limit is not None and (worst > limit if q.largest else worst < limit)


def _across(direction: FloatArray, vectors: FloatArray) -> FloatArray:
    """The parts (N, 3) of ``vectors`` (N, 3) across the unit ``direction`` (N, 3)."""
    return vectors - direction * np.einsum("ij,ij->i", direction, vectors)[:, None]


def quantities(velocity: FloatArray, acceleration: FloatArray, jerk: FloatArray,
               snap: FloatArray, limits: Limits) -> dict[str, FloatArray]:
    """Each checked quantity (N,) from the velocity, acceleration, jerk and snap (N, 3),
    SI units, by the field names of :class:`FeasibilityReport` (module docstring)."""
    drag = np.asarray(limits.drag)
    thrust = acceleration + np.array([0.0, 0.0, GRAVITY]) + drag * velocity
    size = np.linalg.norm(thrust, axis=1)
    turn = jerk + drag * acceleration
    direction = thrust / size[:, None]
    sideways = _across(direction, turn)
    growth = np.einsum("ij,ij->i", direction, turn)  # d|f|/dt
    tilt_acceleration = (_across(direction, snap + drag * jerk)
                         - 2.0 * (growth / size)[:, None] * sideways)
    return {
        "max_speed": np.linalg.norm(velocity, axis=1),
        "max_acceleration": np.linalg.norm(acceleration, axis=1),
        "max_jerk": np.linalg.norm(jerk, axis=1),
        "max_thrust_to_weight": size / GRAVITY,
        "min_thrust_to_weight": size / GRAVITY,
        "max_tilt": np.arctan2(np.hypot(thrust[:, 0], thrust[:, 1]), thrust[:, 2]),
        "max_body_rate": np.linalg.norm(sideways, axis=1) / size,
        "max_angular_acceleration": np.linalg.norm(tilt_acceleration, axis=1) / size,
    }


def _within(velocity: FloatArray, acceleration: FloatArray, jerk: FloatArray,
            snap: FloatArray, limits: Limits) -> bool:
    """Whether every quantity is within ``limits``."""
    series = quantities(velocity, acceleration, jerk, snap, limits)
    return not any(_breaks(q, float(series[q.field].max() if q.largest
                                    else series[q.field].min()), limits)
                   for q in _QUANTITIES)


def slowest_feasible_scale(trajectory: Trajectory, limits: Limits, dt: float = 0.01,
                           largest: float = 1e3) -> float | None:
    """The least factor ``k >= 1`` by which flying ``trajectory`` ``k`` times slower keeps
    every sampled quantity within ``limits`` (to 0.1 %), or None when even ``largest``
    does not (e.g. a thrust floor that slowing down cannot meet)."""
    _, v, a, j, s = _motion(trajectory, dt)

    def ok(k: float) -> bool:
        return _within(v / k, a / k**2, j / k**3, s / k**4, limits)

    if ok(1.0):
        return 1.0
    if not ok(largest):
        return None
    low, high = 1.0, largest
    while high / low > 1.001:
        middle = math.sqrt(low * high)
        low, high = (low, middle) if ok(middle) else (middle, high)
    return high
