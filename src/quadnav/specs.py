"""Specs such as ``forest:size=20x20x6,seed=3`` or ``helix:radius=1,laps=2``: declaring,
parsing and formatting their ``key=value`` parameter lists.

Built-in worlds (:mod:`quadnav.world.builtin`) and built-in references
(:mod:`quadnav.trajectory.references.builtin`) are both named by such a spec. A value is an
``int``, a ``float``, a size ``WxDxH`` (three floats, metres), a grid ``NxM`` (two ints)
or one of a few words (e.g. an axis ``x``, ``y`` or ``z``). A size or grid is a tuple;
its range applies to every part. Every parameter has a stated range (or its list of
words), checked before anything is built, so that no spec can ask for more than the
machine has.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from quadnav.limits import SEED, Range

Value = Any  # int | float | str | tuple[float, float, float] | tuple[int, int]


class SpecError(Exception):
    """A spec that names a world or reference correctly but asks for something it cannot
    build.

    Each registry turns it into a :class:`~quadnav.errors.QuadnavError` naming the spec.
    """


@dataclass(frozen=True)
class Kind:
    """How a parameter's value is written.

    Attributes:
        label: how the type is shown to users: ``int``, ``float``, ``WxDxH``, ``NxM`` or
            the words allowed, e.g. ``x|y|z``.
        parts: numbers in the value (1 for a scalar), joined by ``x``.
        integer: whether the numbers are ints rather than floats.
        choices: the words a value may be (lower case), for a word rather than numbers.
    """

    label: str
    parts: int = 1
    integer: bool = False
    choices: tuple[str, ...] = ()

    def parse(self, text: str) -> Value:
        """The value written as ``text``; ValueError saying what was expected."""
        if self.choices:
            word = text.strip().lower()
            if word not in self.choices:
                raise ValueError(f"expected {self.expected()}, got {text!r}")
            return word
        pieces = text.lower().split("x") if self.parts > 1 else [text]
        try:
            if len(pieces) != self.parts:
                raise ValueError
            numbers = [int(p) if self.integer else float(p) for p in pieces]
        except ValueError:
            raise ValueError(f"expected {self.expected()}, got {text!r}") from None
        if not all(math.isfinite(n) for n in numbers):
            raise ValueError(f"expected {self.expected()}, got {text!r}")
        return numbers[0] if self.parts == 1 else tuple(numbers)

    def format(self, value: Value) -> str:
        """``value`` written so that :meth:`parse` reads it back exactly."""
        if self.choices:
            return str(value)
        numbers = value if self.parts > 1 else (value,)
        return "x".join(str(n) if self.integer else _format_float(n) for n in numbers)

    def expected(self) -> str:
        """What a value of this kind is, in words, e.g. ``a number`` or ``one of x, y, z``."""
        if self.choices:
            return "one of " + ", ".join(self.choices)
        number = "an integer" if self.integer else "a number"
        if self.parts == 1:
            return number
        numbers = "integers" if self.integer else "numbers"
        return f"{self.label} ({self.parts} {numbers} joined by 'x')"


INT = Kind("int", integer=True)
FLOAT = Kind("float")
SIZE = Kind("WxDxH", parts=3)
GRID = Kind("NxM", parts=2, integer=True)
#: One of the world axes.
AXIS = Kind("x|y|z", choices=("x", "y", "z"))


def _format_float(number: float) -> str:
    """Shortest text that reads back as ``number``, without a trailing ``.0``."""
    text = repr(float(number))
    return text.removesuffix(".0")


@dataclass(frozen=True)
class Param:
    """One parameter of a built-in world or reference.

    Attributes:
        name: the key in a spec.
        kind: how the value is written.
        default: value used when the spec leaves the key out.
        help: one line for ``quadnav worlds`` or ``quadnav references``, with units.
        range: the values every part may take (None for a word: its kind's choices).
    """

    name: str
    kind: Kind
    default: Value
    help: str
    range: Range | None = None

    def __post_init__(self) -> None:
        if (self.range is None) != bool(self.kind.choices):
            raise ValueError(f"parameter {self.name!r}: a range is needed exactly when the "
                             "value is numbers")

    def parse(self, text: str) -> Value:
        """The value written as ``text``, checked against the range; SpecError if bad."""
        try:
            value = self.kind.parse(text)
        except ValueError as error:
            raise SpecError(f"{self.name}: {error}") from None
        if self.range is None:
            return value
        parts = value if self.kind.parts > 1 else (value,)
        if not all(part in self.range for part in parts):
            every = "every part " if self.kind.parts > 1 else ""
            raise SpecError(f"{self.name}: expected {every}{self.range.describe()}, got {text}")
        return value

    def format(self, value: Value) -> str:
        """``value`` as it would be written in a spec."""
        return self.kind.format(value)

    def allowed(self) -> str:
        """The values accepted, in words, e.g. ``from 0.01 to 1,000 m`` (for each part of
        a size or grid: ``each from ...``) or ``one of x, y, z``."""
        if self.range is None:
            return self.kind.expected()
        return ("each " if self.kind.parts > 1 else "") + self.range.describe()


@dataclass(frozen=True)
class ParamInfo:
    """A parameter as ``quadnav worlds`` and ``quadnav references`` show it; every field
    is display text.

    Attributes:
        name: the key in a spec, e.g. ``size``.
        type: ``int``, ``float``, ``WxDxH``, ``NxM`` or the words allowed (``x|y|z``).
        default: the default as written in a spec, e.g. ``20x20x6``.
        help: one line, with units.
        range: the values accepted (for each part of a size or grid), e.g.
            ``from 2 to 10,000 m``.
    """

    name: str
    type: str
    default: str
    help: str
    range: str


@dataclass(frozen=True)
class SpecInfo:
    """A built-in world or reference as ``quadnav worlds`` or ``quadnav references``
    shows it.

    Attributes:
        name: its name, the part of a spec before ``:``.
        summary: one line saying what it is.
        params: its parameters, in canonical order.
    """

    name: str
    summary: str
    params: tuple[ParamInfo, ...]


def describe_params(params: Sequence[Param]) -> tuple[ParamInfo, ...]:
    """``params`` as display text, in order."""
    return tuple(ParamInfo(p.name, p.kind.label, p.format(p.default), p.help, p.allowed())
                 for p in params)


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


def canonical_spec(name: str, params: Sequence[Param], rest: str | None) -> tuple[str, dict]:
    """The canonical spec (``name:`` and every parameter, :func:`format_values`) and the
    values of a spec ``name[:rest]``: ``rest`` is the text after the ``:`` (None without
    one: every default). SpecError as :func:`parse_values`."""
    values = ({p.name: p.default for p in params} if rest is None
              else parse_values(params, rest))
    return f"{name}:{format_values(params, values)}", values
