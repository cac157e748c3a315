"""The checks of a mission file's values (pydantic validators), each against the range its
flag has (:mod:`quadnav.limits`), with quadnav's own one-line messages."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

from pydantic import BeforeValidator, ValidationInfo
from pydantic_core import PydanticCustomError

from quadnav.errors import QuadnavError
from quadnav.limits import COORDINATE, SPEED, Range, Speed, is_number, speed_value


def fail(message: str) -> PydanticCustomError:
    """A refusal whose message is ``message`` as it is (pydantic adds nothing)."""
    return PydanticCustomError("quadnav", message)


def number(allowed: Range, optional: bool = False) -> BeforeValidator:
    """A number in ``allowed`` (a whole one if it says so), or None if ``optional``."""
    def check(value: Any) -> float | None:
        if value is None and optional:
            return None
        if not is_number(value) or value not in allowed:
            raise fail(f"expected {allowed.describe()}, got {value!r}")
        return int(value) if allowed.whole else float(value)
    return BeforeValidator(check)


def vector(allowed: Range, names: str, optional: bool = False) -> BeforeValidator:
    """Three numbers, each in ``allowed``, written ``[names]``, or None if ``optional``."""
    def check(value: Any) -> tuple[float, float, float] | None:
        if value is None and optional:
            return None
        if not (isinstance(value, list | tuple) and len(value) == 3
                and all(is_number(v) and v in allowed for v in value)):
            raise fail(f"expected [{names}], each {allowed.describe()}, got {value!r}")
        x, y, z = (float(v) for v in value)
        return x, y, z
    return BeforeValidator(check)


def text(check_name: Callable[[str], object] | None = None,
         optional: bool = False) -> BeforeValidator:
    """A string, checked by ``check_name`` (QuadnavError for a bad one) if given, or None
    if ``optional``."""
    def check(value: Any) -> str | None:
        if value is None and optional:
            return None
        if not isinstance(value, str) or not value.strip():
            raise fail(f"expected a string, got {value!r}")
        if check_name is not None:
            try:
                check_name(value)
            except QuadnavError as error:
                if getattr(error, "details", None):
                    raise  # a plug-in's own traceback: shown as it is
                raise fail(str(error)) from None
        return value
    return BeforeValidator(check)


def choice(names: Callable[[], list[str] | tuple[str, ...]]) -> Callable[[str], None]:
    """A check for :func:`text`: one of ``names()`` (asked when checked: registries grow)."""
    def check(value: str) -> None:
        if value not in names():
            raise QuadnavError(f"expected one of {', '.join(names())}, got {value!r}")
    return check


def flag(value: Any) -> bool:
    """true or false."""
    if not isinstance(value, bool):
        raise fail(f"expected true or false, got {value!r}")
    return value


def top_speed(value: Any) -> Speed:
    """A top speed: a number in :data:`~quadnav.limits.SPEED` or ``"max"``
    (:func:`~quadnav.limits.speed_value`)."""
    found = speed_value(value) if is_number(value) or isinstance(value, str) else None
    if found is None:
        raise fail(f"expected {SPEED.describe()} or \"max\", got {value!r}")
    return found


def file(value: Any, info: ValidationInfo) -> Any:
    """:func:`located` against the mission file's folder, for a string read from one; any
    other value as it is."""
    folder = (info.context or {}).get("folder")
    if not isinstance(value, str) or folder is None:
        return value
    return located(value, folder)


def located(value: str, folder: str | Path) -> str:
    """``value`` naming an existing file relative to ``folder``, or a plug-in in such a file
    (``path/to/file.py:Name(...)``): the same with the file's absolute path; any other
    value as it is (a preset, a built-in world, a course map, a module)."""
    where, colon, name = value.partition(":")
    named, rest = (where, colon + name) if colon and where.endswith(".py") else (value, "")
    path = Path(folder) / named
    if Path(named).is_absolute() or not path.is_file():
        return value
    return os.path.abspath(path) + rest


def table_or_text(value: Any) -> str | dict | None:
    """A name or file (a non-empty string), a table, or None."""
    if value is None or isinstance(value, dict):
        return value
    if isinstance(value, str) and value.strip():
        return value
    raise fail(f"expected a name, a file or a table, got {value!r}")


#: A point, m, or None: the mission's default for it.
Point = Annotated[tuple[float, float, float] | None,
                  vector(COORDINATE, "x, y, z", optional=True)]
#: A file (resolved against the mission file's folder) or a name.
FileOrName = Annotated[str, text(), BeforeValidator(file)]
#: A file (likewise), a name or a table of keys, or None: the mission's default.
TextOrTable = Annotated[str | dict | None, BeforeValidator(table_or_text),
                        BeforeValidator(file)]


