"""Dataclasses from TOML files: vehicle parameters and controller gains.

A config dataclass has fields that are numbers, strings, read-only float64 arrays of a
fixed length, or nested config dataclasses (one TOML table each). :func:`from_table`
fills one from a TOML table on top of a base value, so a file may set just the keys it
changes. Every mistake (an unknown key, a wrong type, a vector of the wrong length, a
value out of range) is a :class:`~quadnav.errors.QuadnavError` naming the file and key.
"""

from __future__ import annotations

import dataclasses
import re
import tomllib
from enum import Enum
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from quadnav.arrays import read_only
from quadnav.errors import QuadnavError
from quadnav.inputfiles import not_a_file, special_file
from quadnav.limits import is_number

C = TypeVar("C")


def frozen_vector(values: ArrayLike, length: int) -> NDArray[np.float64]:
    """A read-only float64 copy of ``values`` with shape ``(length,)``."""
    array = np.array(values, dtype=np.float64).reshape(length)
    return read_only(array)


def vector_field(*values: float) -> Any:
    """A dataclass field defaulting to a fresh read-only vector of ``values``."""
    return dataclasses.field(default_factory=lambda: frozen_vector(values, len(values)))


def read_toml(path: str | Path) -> dict[str, Any]:
    """The table of the TOML file at ``path``; QuadnavError naming the file and line."""
    path = Path(path)
    kind = special_file(path)
    if kind is not None:
        raise QuadnavError(f"{path}: {not_a_file(kind, 'a TOML file')}")
    try:
        with path.open("rb") as file:
            return tomllib.load(file)
    except OSError as error:
        raise QuadnavError(f"{path}: cannot read: {error.strerror}") from None
    except tomllib.TOMLDecodeError as error:
        raise QuadnavError(f"{path}: not valid TOML: {error}") from None
    except ValueError:  # int() refuses more than 4,300 digits
        raise QuadnavError(f"{path}: not valid TOML: a number with too many digits") from None


def _value(current: Any, raw: Any, where: str) -> Any:
    if isinstance(current, np.ndarray):
        numbers = raw if isinstance(raw, list) else None
        if (numbers is None or len(numbers) != len(current)
                or not all(is_number(v, finite=True) for v in numbers)):
            raise QuadnavError(f"{where}: expected a list of {len(current)} numbers, got {raw!r}")
        return frozen_vector(numbers, len(current))
    if isinstance(current, str):
        if not isinstance(raw, str):
            raise QuadnavError(f"{where}: expected a string, got {raw!r}")
        return raw
    if isinstance(current, bool):
        if not isinstance(raw, bool):
            raise QuadnavError(f"{where}: expected true or false, got {raw!r}")
        return raw
    if isinstance(current, int):
        if not isinstance(raw, int) or isinstance(raw, bool):
            raise QuadnavError(f"{where}: expected a whole number, got {raw!r}")
        return raw
    if not is_number(raw, finite=True):
        raise QuadnavError(f"{where}: expected a number, got {raw!r}")
    return float(raw)


def from_table(base: C, table: dict[str, Any], where: str) -> C:
    """``base`` (a config dataclass) with the keys of ``table`` replaced.

    ``where`` prefixes messages, e.g. ``"gains.toml"``; nested tables add ``[name]``.
    """
    fields = {f.name: f for f in dataclasses.fields(base) if f.init}
    changes: dict[str, Any] = {}
    for key, raw in table.items():
        if key not in fields:
            raise QuadnavError(f"{where}: unknown key {key!r}; expected one of "
                               f"{', '.join(fields)}")
        current = getattr(base, key)
        if dataclasses.is_dataclass(current):
            if not isinstance(raw, dict):
                raise QuadnavError(f"{where}: {key} must be a table [{key}]")
            changes[key] = from_table(current, raw, f"{where} [{key}]")
        else:
            changes[key] = _value(current, raw, f"{where}: {key}")
    try:
        return dataclasses.replace(base, **changes)
    except QuadnavError as error:
        raise QuadnavError(f"{where}: {error}") from None


def as_plain(value: Any) -> Any:
    """A config dataclass (or any nesting of dataclasses, arrays, enums and numbers) as
    JSON-ready dicts, lists and scalars."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: as_plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Enum):
        return value.value
    return value


def toml_text(value: Any, comment: str = "") -> str:
    """A config dataclass (or a JSON-ready dict of numbers, strings, lists and nested dicts)
    as TOML text that :func:`read_toml` and :func:`from_table` read back exactly, written
    by tomli-w (scalars and lists first, then one ``[table]`` per nested dict; a list of
    numbers on one line), after ``comment`` as ``#`` lines."""
    import tomli_w

    lines = "".join(f"# {line}".rstrip() + "\n" for line in comment.splitlines())
    return lines + _NUMBER_LIST.sub(_one_line, tomli_w.dumps(as_plain(value)))


#: A list of numbers as tomli-w writes it, an item per line.
_NUMBER_LIST = re.compile(r"\[\n((?:[ \t]+[-+0-9.eE]+,\n)+)\]")


def _one_line(match: re.Match) -> str:
    return "[" + ", ".join(item.strip().rstrip(",") for item in match.group(1).splitlines()) + "]"


def require(checks: list[tuple[bool, str]]) -> None:
    """Raise QuadnavError with the message of the first failed ``(ok, message)`` check."""
    for ok, message in checks:
        if not ok:
            raise QuadnavError(message)
