"""Parameters of built-in worlds: declaring, parsing and formatting ``key=value`` lists.

A value is an ``int``, a ``float``, a size ``WxDxH`` (three floats, metres) or a grid
``NxM`` (two ints). A size or grid is a tuple; its range applies to every part. Every
parameter has a stated range, checked before anything is built, so that no spec can
ask for more than the machine has.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from quadnav.limits import COORDINATE, SEED, Range

Value = Any  # int | float | tuple[float, float, float] | tuple[int, int]


class SpecError(Exception):
    """A spec that names a world correctly but asks for something it cannot build.

    The registry turns it into a :class:`~quadnav.errors.MapError` naming the spec.
    """


@dataclass(frozen=True)
class Kind:
    """How a parameter's value is written.

    Attributes:
        label: how the type is shown to users: ``int``, ``float``, ``WxDxH`` or ``NxM``.
        parts: numbers in the value (1 for a scalar), joined by ``x``.
        integer: whether the numbers are ints rather than floats.
    """

    label: str
    parts: int = 1
    integer: bool = False

    def parse(self, text: str) -> Value:
        """The value written as ``text``; ValueError saying what was expected."""
        pieces = text.lower().split("x") if self.parts > 1 else [text]
        try:
            if len(pieces) != self.parts:
                raise ValueError
            numbers = [int(p) if self.integer else float(p) for p in pieces]
        except ValueError:
            raise ValueError(f"expected {self._expected()}, got {text!r}") from None
        if not all(math.isfinite(n) for n in numbers):
            raise ValueError(f"expected {self._expected()}, got {text!r}")
        return numbers[0] if self.parts == 1 else tuple(numbers)

    def format(self, value: Value) -> str:
        """``value`` written so that :meth:`parse` reads it back exactly."""
        numbers = value if self.parts > 1 else (value,)
        return "x".join(str(n) if self.integer else _format_float(n) for n in numbers)

    def _expected(self) -> str:
        number = "an integer" if self.integer else "a number"
        if self.parts == 1:
            return number
        numbers = "integers" if self.integer else "numbers"
        return f"{self.label} ({self.parts} {numbers} joined by 'x')"


INT = Kind("int", integer=True)
FLOAT = Kind("float")
SIZE = Kind("WxDxH", parts=3)
GRID = Kind("NxM", parts=2, integer=True)


def _format_float(number: float) -> str:
    """Shortest text that reads back as ``number``, without a trailing ``.0``."""
    text = repr(float(number))
    return text.removesuffix(".0")


@dataclass(frozen=True)
class Param:
    """One parameter of a built-in world.

    Attributes:
        name: the key in a spec.
        kind: how the value is written.
        default: value used when the spec leaves the key out.
        help: one line for ``quadnav worlds``, with units.
        range: the values every part may take.
    """

    name: str
    kind: Kind
    default: Value
    help: str
    range: Range

    def parse(self, text: str) -> Value:
        """The value written as ``text``, checked against the range; SpecError if bad."""
        try:
            value = self.kind.parse(text)
        except ValueError as error:
            raise SpecError(f"{self.name}: {error}") from None
        parts = value if self.kind.parts > 1 else (value,)
        if not all(part in self.range for part in parts):
            every = "every part " if self.kind.parts > 1 else ""
            raise SpecError(f"{self.name}: expected {every}{self.range.describe()}, got {text}")
        return value

    def format(self, value: Value) -> str:
        """``value`` as it would be written in a spec."""
        return self.kind.format(value)


def sizes(least: float) -> Range:
    """The range of a map's side: ``least`` to the coordinate range's 10 km, metres."""
    return Range(least, COORDINATE.high, "m")


#: The ``seed`` parameter of the worlds that draw their layout at random.
SEED_PARAM = Param("seed", INT, 0, "random seed", SEED)


def parse_values(params: Sequence[Param], text: str) -> dict[str, Value]:
    """Values for every parameter from ``key=value,key=value`` (missing keys -> defaults).

    Raises SpecError for an item that is not ``key=value``, an unknown or repeated key,
    or a bad value.
    """
    by_name = {p.name: p for p in params}
    given: dict[str, Value] = {}
    for item in text.split(","):
        key, equals, raw = (part.strip() for part in item.partition("="))
        if not item.strip():
            raise SpecError("empty parameter: expected key=value")
        if not equals or not key or not raw:
            raise SpecError(f"expected key=value, got {item.strip()!r}")
        if key not in by_name:
            valid = ", ".join(by_name) or "none"
            raise SpecError(f"unknown parameter {key!r} (valid: {valid})")
        if key in given:
            raise SpecError(f"parameter {key!r} given twice")
        given[key] = by_name[key].parse(raw)
    return {p.name: given.get(p.name, p.default) for p in params}


def format_values(params: Sequence[Param], values: dict[str, Value]) -> str:
    """``key=value,...`` for every parameter, in declaration order."""
    return ",".join(f"{p.name}={p.format(values[p.name])}" for p in params)
