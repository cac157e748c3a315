"""Controller gains and limits: :class:`Gains`, loadable from TOML.

Gains are per axis ``(x, y, z)`` (world axes for position and velocity, body axes for
attitude and rate). The position and velocity loops have a P, I and D gain per axis:
the 18 gains course projects tune by hand. The attitude and rate gains are normalised
by the vehicle (the rate loop asks for angular accelerations, which the inertia turns
into torques), so one set serves vehicles of different sizes. The defaults are tuned to
track minimum-snap trajectories at 2 m/s and more on the ``tello`` preset.

A TOML file sets any keys on top of the gains tuned for the vehicle, e.g.::

    [position]
    kp = [1.5, 1.5, 2.0]

    [velocity]
    ki = [0.5, 0.5, 1.0]

    [limits]
    tilt_max_deg = 30.0

The one way to get the gains a controller flies a vehicle with, the vehicle's own set with a
file's or a table's keys on top, is :func:`quadnav.control.registry.controller_gains`
(``controller_gains("cascade", vehicle, "my_gains.toml")``); this module holds the gains'
types and reads the shipped sets and tables.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import TypeVar

from quadnav.arrays import FloatArray
from quadnav.config import as_plain, from_table, frozen_vector, read_toml, require, vector_field
from quadnav.limits import ACCELERATION, GAIN, RATE, SPEED, Range, format_number

C = TypeVar("C")
#: A body rate setpoint's bound, degrees/s (ten turns a second at most).
RATE_MAX = Range(0.0, 3600.0, "deg/s", above_low=True)
#: Where the cascade's gain sets are shipped (:func:`shipped`).
CASCADE_SETS = "presets"


@dataclass(frozen=True, eq=False)
class PID:
    """Three per-axis PID gains and the integral's bound.

    Attributes:
        kp: (3,) proportional gains.
        ki: (3,) integral gains.
        kd: (3,) derivative gains.
        integral_limit: (3,) largest magnitude of ``ki`` times the integral, in the
            loop's output unit.
    """

    kp: FloatArray = vector_field(0.0, 0.0, 0.0)
    ki: FloatArray = vector_field(0.0, 0.0, 0.0)
    kd: FloatArray = vector_field(0.0, 0.0, 0.0)
    integral_limit: FloatArray = vector_field(1.0, 1.0, 1.0)

    def __post_init__(self) -> None:
        require(gain_checks(self, ("kp", "ki", "kd", "integral_limit")))


def gain_checks(gains: object, names: tuple[str, ...]) -> list[tuple[bool, str]]:
    """``(ok, message)`` for each (3,) field of ``gains`` named in ``names``: every value in
    :data:`~quadnav.limits.GAIN` (a gain of 1e300 would fly, and diverge)."""
    return [(all(float(v) in GAIN for v in getattr(gains, name)),
             f"{name}: expected each value {GAIN.describe()}, got "
             f"{_listed(getattr(gains, name))}") for name in names]


def _listed(values: FloatArray) -> str:
    """``[1, 2.5, 1e+300]``: each value with every digit it has."""
    return "[" + ", ".join(format_number(float(v)) for v in values) + "]"


@dataclass(frozen=True, eq=False)
class Saturations:
    """Saturations of the cascade (a gains file's ``[limits]`` table).

    Attributes:
        speed_xy: largest horizontal velocity setpoint, m/s.
        speed_up: largest climb rate setpoint, m/s.
        speed_down: largest descent rate setpoint, m/s. These limits clip the whole
            setpoint, the trajectory's feed-forward included, so they sit above the speeds
            trajectories are made with.
        acceleration_xy: largest horizontal acceleration setpoint, m/s^2.
        tilt_max_deg: largest angle between the thrust and the vertical, degrees.
        thrust_min: smallest collective thrust, fraction of the rotors' total.
        thrust_max: largest collective thrust, fraction of the total (the rest is kept
            for attitude control).
        rate_max_deg: (3,) largest body rate setpoints about x, y, z, degrees/s.
        derivative_cutoff_hz: cut-off of the first-order filters on derivative terms, Hz.
    """

    speed_xy: float = 8.0
    speed_up: float = 5.0
    speed_down: float = 5.0
    acceleration_xy: float = 12.0
    tilt_max_deg: float = 45.0
    thrust_min: float = 0.05
    thrust_max: float = 0.9
    rate_max_deg: FloatArray = vector_field(360.0, 360.0, 180.0)
    derivative_cutoff_hz: float = 30.0

    def __post_init__(self) -> None:
        ranges = {"speed_xy": SPEED, "speed_up": SPEED, "speed_down": SPEED,
                  "acceleration_xy": ACCELERATION, "derivative_cutoff_hz": RATE}
        require([(getattr(self, k) in allowed, f"{k}: expected {allowed.describe()}, got "
                  f"{format_number(getattr(self, k))}") for k, allowed in ranges.items()] + [
            (0 < self.tilt_max_deg < 90, f"tilt_max_deg must be in (0, 90), got "
                                         f"{self.tilt_max_deg}"),
            (0 <= self.thrust_min < self.thrust_max <= 1,
             f"expected 0 <= thrust_min < thrust_max <= 1, got {self.thrust_min} and "
             f"{self.thrust_max}"),
            (all(float(v) in RATE_MAX for v in self.rate_max_deg),
             f"rate_max_deg: expected each value {RATE_MAX.describe()}, got "
             f"{_listed(self.rate_max_deg)}"),
        ])


def _pid(kp: tuple, ki: tuple = (0.0,) * 3, kd: tuple = (0.0,) * 3,
         integral_limit: tuple = (1.0,) * 3) -> PID:
    return PID(*(frozen_vector(v, 3) for v in (kp, ki, kd, integral_limit)))


@dataclass(frozen=True, eq=False)
class Gains:
    """The cascade's gains: position -> velocity -> attitude -> body rate.

    Attributes:
        position: position error (m) to velocity setpoint (m/s) PID, world axes.
        velocity: velocity error (m/s) to acceleration setpoint (m/s^2) PID, world axes.
        attitude_kp: (3,) attitude error (rad) to body rate setpoint (rad/s), body axes.
        rate: body rate error (rad/s) to angular acceleration (rad/s^2) PID, body axes.
        limits: saturations.
    """

    position: PID = field(default_factory=lambda: _pid((1.8, 1.8, 2.5)))
    velocity: PID = field(default_factory=lambda: _pid(
        (5.0, 5.0, 6.0), (1.0, 1.0, 2.0), (0.05, 0.05, 0.0), (3.0, 3.0, 4.0)))
    attitude_kp: FloatArray = vector_field(12.0, 12.0, 5.0)
    rate: PID = field(default_factory=lambda: _pid(
        (40.0, 40.0, 15.0), (10.0, 10.0, 5.0), (0.3, 0.3, 0.0), (30.0, 30.0, 10.0)))
    limits: Saturations = field(default_factory=Saturations)

    def __post_init__(self) -> None:
        require(gain_checks(self, ("attitude_kp",)))

    def replace(self, **changes: object) -> Gains:
        """A copy with some fields changed (see :func:`dataclasses.replace`)."""
        return dataclasses.replace(self, **changes)

    def as_dict(self) -> dict:
        """JSON-ready nested dict, the layout of a gains TOML file."""
        return as_plain(self)


def course_gain_names() -> list[str]:
    """Names of the shipped course gain tables (``p2a-starter``, ``p2a-ankx22``, ...): the
    18 position and velocity gains of the WPI RBE595 starter and of published student teams,
    each file stating its source; usable wherever a gains file is (``--gains NAME``)."""
    return sorted(toml_names("course"))


def shipped(folder: str):
    """The folder ``folder`` (e.g. ``presets``) of the files shipped in quadnav.control."""
    return resources.files("quadnav.control").joinpath(*folder.split("/"))


def toml_names(folder: str) -> list[str]:
    """The names of the TOML files shipped in ``folder`` (:func:`shipped`; none if it is
    not there)."""
    files = shipped(folder)
    if not files.is_dir():
        return []
    return [p.name.removesuffix(".toml") for p in files.iterdir() if p.name.endswith(".toml")]


def shipped_table(folder: str, name: str) -> dict:
    """The table of the shipped TOML file ``folder/name.toml``."""
    with resources.as_file(shipped(folder) / f"{name}.toml") as real:
        return read_toml(real)


def gain_table(source: str | Path) -> tuple[dict, str]:
    """The keys a gains source sets, and how messages name it: a course gain table by name
    (:func:`course_gain_names`) or a TOML file."""
    if str(source) in course_gain_names():
        return shipped_table("course", str(source)), f"gain table {source}"
    return read_toml(source), str(source)


def gain_set(defaults: C, folder: str, name: str) -> C:
    """A controller's ``defaults`` (a config dataclass) with its shipped gain set
    ``folder/name.toml`` set on top, or the defaults alone when it ships no set of that
    name."""
    if name not in toml_names(folder):
        return defaults
    return from_table(defaults, shipped_table(folder, name), f"gain set {name}")
