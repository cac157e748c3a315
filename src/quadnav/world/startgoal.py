"""RBE595 start/goal files: lines ``start: (x, y, z)`` and ``goal: (x, y, z)``.

Blank lines and ``#`` comments are allowed; the parentheses and spaces are optional.
In the course's Tello maps ``z = 0`` means "take off (or land) here".
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from quadnav.errors import MapError
from quadnav.world import courses
from quadnav.world.model import World
from quadnav.world.reading import (
    check_coordinates,
    check_line_length,
    decode_text,
    parse_float,
    read_file,
    text_lines,
)

_LINE = re.compile(r"^\s*(start|goal)\s*:\s*\(?([^()]*)\)?\s*$", re.IGNORECASE)


def parse_start_goal(text: str, source: str) -> tuple[np.ndarray, np.ndarray]:
    """(start, goal), each (3,) metres, from the text of a start/goal file."""
    found: dict[str, np.ndarray] = {}
    for number, raw in enumerate(text_lines(text), start=1):
        check_line_length(raw, source, number)
        content = raw.split("#", 1)[0]
        if not content.strip():
            continue
        match = _LINE.match(content)
        if match is None:
            raise MapError(source, "expected 'start: (x, y, z)' or 'goal: (x, y, z)', "
                           f"got {content.strip()[:40]!r}", number)
        key = match.group(1).lower()
        if key in found:
            raise MapError(source, f"a second '{key}' line: expected one", number)
        parts = [p for p in re.split(r"[,\s]+", match.group(2).strip()) if p]
        if len(parts) != 3:
            raise MapError(source, f"{key}: expected 3 numbers (x, y, z), got {len(parts)}",
                           number)
        values = [parse_float(p, source, number, key) for p in parts]
        found[key] = np.array(check_coordinates(values, source, number, key))
    for key in ("start", "goal"):
        if key not in found:
            raise MapError(source, f"no '{key}: (x, y, z)' line")
    return found["start"], found["goal"]


def read_start_goal(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """(start, goal), each (3,) metres, from an RBE595 start/goal file or a course one
    named ``course:NAME`` (offline: fetched before)."""
    if courses.is_course_name(path):
        data, _ = courses.read_course_file(str(path), courses.START_GOAL)
    else:
        data = read_file(path)
    return parse_start_goal(decode_text(data, str(path)), str(path))


def query_ends(world: World, start: ArrayLike | None = None, goal: ArrayLike | None = None,
               start_goal: str | Path | None = None
               ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The start and goal of a query on ``world``, each (3,) m or None (none known): each
    one given, else that of the start/goal file ``start_goal`` (a file or ``course:NAME``),
    else the map's own (the one rule of every command and the library)."""
    ends = [world.start, world.goal]
    if start_goal is not None:
        ends = list(read_start_goal(start_goal))
    for k, given in enumerate((start, goal)):
        if given is not None:
            ends[k] = np.array(given, dtype=np.float64)
    return ends[0], ends[1]
