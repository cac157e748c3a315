"""Built-in references, made from a spec such as ``helix:radius=1,speed=1,laps=2,climb=1``:
:func:`build_reference`, and :func:`load_reference` for a spec or a file.

A spec is a reference's name, optionally followed by ``:`` and ``key=value`` pairs joined
by commas (:mod:`quadnav.specs`); left-out keys take their defaults, and every value has
a stated range (``quadnav references`` lists them). A built reference is named by its
canonical spec, which lists every parameter.

* ``hover`` holds still at ``(0, 0, height)``; ``step`` holds still there and, at ``at`` s,
  its position jumps by ``size`` along ``axis`` while its velocity and acceleration stay 0
  (a true step, as the course tunes gains with): :class:`StepReference`.
* ``circle``, ``helix``, ``figure8`` and ``lissajous`` fly a shape ``p(phi)`` from
  ``(0, 0, height)`` by a smooth time law (:class:`~quadnav.trajectory.references.timelaw.PhaseLaw`:
  from rest, up to the cruise rate over ``ramp`` s, and back to rest over the last
  ``ramp`` s), with exact derivatives: :class:`ShapedReference`.

Every built-in reference keeps the yaw at 0.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.limits import MAX_DURATION, SPEED, Range
from quadnav.plugins import Registry
from quadnav.specs import (
    AXIS,
    FLOAT,
    INT,
    Param,
    SpecError,
    SpecInfo,
    canonical_spec,
    describe_params,
)
from quadnav.trajectory.references.contract import Reference, Sampling
from quadnav.trajectory.references.plain import (
    flat_reference,
    is_trajectory_class,
    load_trajectory_class,
)
from quadnav.trajectory.references.sampled import (
    COURSE_MP_RATE,
    is_reference_file,
    read_reference_file,
)
from quadnav.trajectory.references.timelaw import PhaseLaw

TWO_PI = 2.0 * math.pi


def _vectors(t: ArrayLike, values: FloatArray) -> FloatArray:
    """``values`` (N, 3) shaped for times ``t``: (3,) for a scalar, (N, 3) for (N,)."""
    return values.reshape((*np.shape(t), 3))


def _zero_yaw(t: ArrayLike) -> FloatArray:
    """Yaw 0 rad at ``t``: a scalar or (N,)."""
    return np.zeros(np.shape(t))


@dataclass(frozen=True, eq=False)
class StepReference(Sampling):
    """Hold still at ``start``; from ``at`` s on, at ``start + jump``. Velocity and
    acceleration are always 0 (the position alone jumps). With no jump: a hover.

    Attributes:
        name: the canonical spec.
        start: (3,) position before the step, m.
        jump: (3,) change of the position at the step, m (zero for a hover).
        at: time of the step, s (> 0).
        duration: s.
    """

    name: str
    start: FloatArray
    jump: FloatArray
    at: float
    duration: float

    @property
    def is_step(self) -> bool:
        """Whether the position jumps (else a hover)."""
        return bool(np.any(self.jump != 0))

    @property
    def target(self) -> FloatArray:
        """(3,) position after the step, m."""
        return self.start + self.jump

    def position(self, t: ArrayLike) -> FloatArray:
        """Position, m, at ``t`` s: scalar -> (3,), (N,) -> (N, 3)."""
        after = np.asarray(t, dtype=np.float64).reshape(-1, 1) >= self.at
        return _vectors(t, self.start + self.jump * after)

    def velocity(self, t: ArrayLike) -> FloatArray:
        """Velocity, m/s: 0."""
        return np.zeros((*np.shape(t), 3))

    def acceleration(self, t: ArrayLike) -> FloatArray:
        """Acceleration, m/s^2: 0."""
        return np.zeros((*np.shape(t), 3))

    def yaw(self, t: ArrayLike) -> FloatArray:
        """Yaw, rad: 0."""
        return _zero_yaw(t)


class Curve(Protocol):
    """A shape: ``phi`` (N,) -> position (N, 3) m and its first two derivatives with
    respect to ``phi``."""

    def __call__(self, phi: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]: ...


@dataclass(frozen=True)
class Helix:
    """``p(phi) = (r sin phi, r (1 - cos phi), height + climb phi / 2 pi)``: round the
    circle of radius ``r`` about ``(0, r)`` from the origin, heading +x, anticlockwise
    seen from above, rising ``climb`` m per lap (0: a circle)."""

    radius: float
    climb: float
    height: float

    def __call__(self, phi: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        r, sin, cos = self.radius, np.sin(phi), np.cos(phi)
        rise = np.full_like(phi, self.climb / TWO_PI)
        zero = np.zeros_like(phi)
        return (np.column_stack([r * sin, r * (1 - cos), self.height + rise * phi]),
                np.column_stack([r * cos, r * sin, rise]),
                np.column_stack([-r * sin, r * cos, zero]))

    def speed(self) -> float:
        """Speed along the helix per unit of phase rate, m/rad: ``|p'(phi)|``."""
        return math.hypot(self.radius, self.climb / TWO_PI)


@dataclass(frozen=True)
class Lissajous:
    """``p(phi) = (ax sin(fx phi), ay sin(fy phi), height + az sin(fz phi))`` from
    ``(0, 0, height)``: amplitudes ``(ax, ay, az)`` m and whole frequencies ``(fx, fy,
    fz)`` per lap of ``2 pi`` (``(size / 2, size / 4, 0)`` and ``(1, 2, 0)``: a
    figure 8, Gerono's lemniscate)."""

    amplitudes: tuple[float, float, float]
    frequencies: tuple[int, int, int]
    height: float

    def __call__(self, phi: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        a, f = np.array(self.amplitudes), np.array(self.frequencies, dtype=np.float64)
        angle = phi[:, None] * f
        position = a * np.sin(angle) + [0.0, 0.0, self.height]
        return position, a * f * np.cos(angle), -a * f**2 * np.sin(angle)


@dataclass(frozen=True, eq=False)
class ShapedReference(Sampling):
    """A shape flown by a time law: position ``p(phi(t))``, velocity
    ``p'(phi) phidot``, acceleration ``p''(phi) phidot^2 + p'(phi) phiddot``, all exact.

    Attributes:
        name: the canonical spec.
        curve: the shape, ``phi -> (p, p', p'')``.
        law: the phase over time.
    """

    name: str
    curve: Curve
    law: PhaseLaw

    @property
    def duration(self) -> float:
        """s."""
        return self.law.duration

    def _states(self, t: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        times = np.asarray(t, dtype=np.float64).reshape(-1)
        phase, rate, change = self.law(times)
        p, slope, bend = self.curve(phase)
        return (p, slope * rate[:, None],
                bend * rate[:, None] ** 2 + slope * change[:, None])

    def position(self, t: ArrayLike) -> FloatArray:
        """Position, m, at ``t`` s: scalar -> (3,), (N,) -> (N, 3)."""
        return _vectors(t, self._states(t)[0])

    def velocity(self, t: ArrayLike) -> FloatArray:
        """Velocity, m/s, at ``t`` s."""
        return _vectors(t, self._states(t)[1])

    def acceleration(self, t: ArrayLike) -> FloatArray:
        """Acceleration, m/s^2, at ``t`` s."""
        return _vectors(t, self._states(t)[2])

    def yaw(self, t: ArrayLike) -> FloatArray:
        """Yaw, rad: 0."""
        return _zero_yaw(t)


# ------------------------------------------------------------------ parameters
#: Heights, amplitudes and sizes, m.
HEIGHT = Range(0.0, 1000.0, "m")
AMPLITUDE = Range(0.0, 1000.0, "m")
EXTENT = Range(0.01, 1000.0, "m")
#: Durations, periods and ramps, s.
DURATION = Range(0.1, MAX_DURATION, "s")
RAMP = Range(0.1, 600.0, "s")
#: Laps of a shape.
LAPS = Range(0.01, 1000.0, "laps")
#: Frequencies of a Lissajous figure, per lap.
FREQUENCY = Range(0, 100, whole=True)


def _height(default: float) -> Param:
    return Param("height", FLOAT, default, "height of the start above z = 0, m", HEIGHT)


def _laps(default: float) -> Param:
    return Param("laps", FLOAT, default, "times round the shape", LAPS)


def _period(default: float) -> Param:
    return Param("period", FLOAT, default, "time of a lap at the cruise rate, s", DURATION)


RAMP_PARAM = Param("ramp", FLOAT, 1.0, "time to speed up from rest, and to slow down to it, s",
                   RAMP)


def _hover(name: str, v: dict[str, Any]) -> Reference:
    start = np.array([0.0, 0.0, v["height"]])
    return StepReference(name, start, np.zeros(3), v["duration"], v["duration"])


def _step(name: str, v: dict[str, Any]) -> Reference:
    if v["size"] == 0:
        raise SpecError("size: expected a step other than 0 m")
    if v["at"] >= v["duration"]:
        raise SpecError(f"at ({v['at']:g} s) must be before the end (duration "
                        f"{v['duration']:g} s)")
    jump = np.zeros(3)
    jump["xyz".index(v["axis"])] = v["size"]
    return StepReference(name, np.array([0.0, 0.0, v["height"]]), jump, v["at"],
                         v["duration"])


def _shaped(name: str, curve: Curve, rate: float, v: dict[str, Any]) -> Reference:
    """``curve`` flown ``v["laps"]`` times at the cruise phase ``rate``, rad/s, with
    ``v["ramp"]``; SpecError if the laps are too short for the ramps or last too long."""
    laps, ramp = v["laps"], v["ramp"]
    lap_time = TWO_PI / rate
    if laps * lap_time < ramp:
        raise SpecError(f"{laps:g} laps take {laps * lap_time:.3g} s at the cruise rate, less "
                        f"than the ramp ({ramp:g} s) that speeding up and slowing down need: "
                        "add laps or shorten the ramp")
    law = PhaseLaw(TWO_PI * laps, rate, ramp)
    if law.duration > MAX_DURATION:
        raise SpecError(f"it lasts {law.duration:.6g} s, longer than the {MAX_DURATION:g} s "
                        "a reference may last: fewer laps, or faster")
    return ShapedReference(name, curve, law)


def _circle(name: str, v: dict[str, Any]) -> Reference:
    return _shaped(name, Helix(v["radius"], 0.0, v["height"]), v["speed"] / v["radius"], v)


def _helix(name: str, v: dict[str, Any]) -> Reference:
    helix = Helix(v["radius"], v["climb"], v["height"])
    return _shaped(name, helix, v["speed"] / helix.speed(), v)


def _figure8(name: str, v: dict[str, Any]) -> Reference:
    size = v["size"]
    return _shaped(name, Lissajous((size / 2, size / 4, 0.0), (1, 2, 0), v["height"]),
                   TWO_PI / v["period"], v)


def _lissajous(name: str, v: dict[str, Any]) -> Reference:
    curve = Lissajous((v["ax"], v["ay"], v["az"]), (v["fx"], v["fy"], v["fz"]), v["height"])
    return _shaped(name, curve, TWO_PI / v["period"], v)


@dataclass(frozen=True)
class ReferenceType:
    """A built-in reference.

    Attributes:
        name: the part of a spec before ``:``.
        summary: one line saying what it flies.
        params: its parameters, in canonical order.
        make: ``make(canonical spec, values) -> Reference``; may raise SpecError.
    """

    name: str
    summary: str
    params: tuple[Param, ...]
    make: Callable[[str, dict[str, Any]], Reference]


_OURS = (
    ReferenceType("hover", "hold still at (0, 0, height)", (
        _height(1.0),
        Param("duration", FLOAT, 5.0, "how long, s", DURATION)), _hover),
    ReferenceType("step", "hover at (0, 0, height); at time 'at' the position jumps by "
                  "'size' along 'axis' (velocity and acceleration stay 0)", (
        Param("axis", AXIS, "x", "axis of the step"),
        Param("size", FLOAT, 1.0, "size of the step, m (negative: backwards)",
              Range(-1000.0, 1000.0, "m")),
        _height(1.0),
        Param("at", FLOAT, 1.0, "time of the step, s", Range(0.0, MAX_DURATION, "s",
                                                             above_low=True)),
        Param("duration", FLOAT, 6.0, "how long, s", DURATION)), _step),
    ReferenceType("circle", "round a horizontal circle from (0, 0, height), heading +x", (
        Param("radius", FLOAT, 1.0, "radius, m", EXTENT),
        Param("speed", FLOAT, 1.0, "cruise speed, m/s", SPEED),
        _laps(1.0), _height(1.0), RAMP_PARAM), _circle),
    ReferenceType("helix", "the circle, climbing 'climb' metres per lap", (
        Param("radius", FLOAT, 1.0, "radius, m", EXTENT),
        Param("speed", FLOAT, 1.0, "cruise speed along the helix, m/s", SPEED),
        _laps(2.0),
        Param("climb", FLOAT, 1.0, "height gained per lap, m (negative: down)",
              Range(-1000.0, 1000.0, "m")),
        _height(0.5), RAMP_PARAM), _helix),
    ReferenceType("figure8", "a horizontal figure 8 (Gerono's lemniscate) through "
                  "(0, 0, height), lobes along x", (
        Param("size", FLOAT, 2.0, "width along x, m (y: half of it)", EXTENT),
        _period(8.0), _laps(1.0), _height(1.0), RAMP_PARAM), _figure8),
    ReferenceType("lissajous", "(ax sin(fx phi), ay sin(fy phi), height + az sin(fz phi)), "
                  "phi 2 pi per lap", (
        Param("ax", FLOAT, 1.0, "amplitude along x, m", AMPLITUDE),
        Param("ay", FLOAT, 1.0, "amplitude along y, m", AMPLITUDE),
        Param("az", FLOAT, 0.3, "amplitude along z, m", AMPLITUDE),
        Param("fx", INT, 1, "cycles along x per lap", FREQUENCY),
        Param("fy", INT, 2, "cycles along y per lap", FREQUENCY),
        Param("fz", INT, 3, "cycles along z per lap", FREQUENCY),
        _period(10.0), _laps(1.0), _height(1.0), RAMP_PARAM), _lissajous),
)
#: The built-in references by name: ours, those of installed packages'
#: ``quadnav.references`` entry points, those registered
#: (``REFERENCES.register(name, reference_type)``).
REFERENCES: Registry[ReferenceType] = Registry(
    "reference", "quadnav.references", {t.name: t for t in _OURS}, expects=ReferenceType)


def reference_names() -> list[str]:
    """Names of the built-in references."""
    return REFERENCES.names()


def describe_references() -> list[SpecInfo]:
    """Every built-in reference with a summary and its parameters."""
    types = {name: REFERENCES.get(name) for name in REFERENCES}
    return [SpecInfo(name, t.summary, describe_params(t.params)) for name, t in types.items()]


def is_builtin_reference(text: str) -> bool:
    """Whether ``text`` names a built-in reference (the part before any ``:``)."""
    return text.partition(":")[0].strip() in REFERENCES


def build_reference(spec: str) -> Reference:
    """The built-in reference ``spec`` describes, named by its canonical spec.

    Raises:
        QuadnavError: an unknown reference or parameter, a repeated parameter, a value of
            the wrong type or out of range, or values it cannot fly (a step at or after
            its end, too few laps for the ramps): one line naming the spec.
    """
    name, colon, rest = (part.strip() for part in spec.partition(":"))
    if name not in REFERENCES:
        raise QuadnavError(f"{spec}: unknown built-in reference {name!r} "
                           f"(known: {', '.join(REFERENCES)})")
    kind = REFERENCES.get(name)
    try:
        canonical, values = canonical_spec(name, kind.params, rest if colon else None)
        return kind.make(canonical, values)
    except SpecError as error:
        raise QuadnavError(f"{spec}: {error}") from None


def load_reference(source: str | Path, rate: float = COURSE_MP_RATE, dt: float | None = None,
                   duration: float | None = None) -> Reference:
    """A reference from a file (quadnav's trajectory.csv, or an MP.csv read at ``rate``
    columns per second, Hz: :func:`~quadnav.trajectory.references.sampled.read_reference_file`), a
    built-in reference spec (:func:`build_reference`), or a trajectory class of your own,
    ``module:Class`` or ``path/to/file.py:Class`` with literal keyword arguments, built
    from them and sampled every ``dt`` s (the control interval) for ``duration`` s or as
    long as it says it lasts (:mod:`quadnav.trajectory.references.plain`).

    Raises:
        QuadnavError: none of these, or a bad one (:class:`~quadnav.plugins.PluginError`
            for a class that fails).
        ValueError: a trajectory class without ``dt``.
    """
    if is_reference_file(source):
        return read_reference_file(source, rate)
    if is_builtin_reference(str(source)):
        return build_reference(str(source))
    if is_trajectory_class(str(source)):
        if dt is None:
            raise ValueError("dt: a trajectory class is sampled every dt s, the control "
                             "interval")
        chosen = load_trajectory_class(str(source))
        return flat_reference(chosen.build(), chosen.text, dt, duration)
    raise QuadnavError(f"{source}: no such file, not a built-in reference (built-in: "
                       f"{', '.join(REFERENCES)}), and not a trajectory class (module:Class or "
                       "path/to/file.py:Class)")
