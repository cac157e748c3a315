"""Checks shared by the map readers: numbers, boxes, and assembling a :class:`World`.

Every problem is raised as :class:`~quadnav.errors.MapError` naming the source and
line; repairs (clipping a block to the boundary, dropping one outside it) are
reported as :class:`~quadnav.errors.MapWarning`.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator, Sequence

import numpy as np

from quadnav.errors import MapError, MapWarning
from quadnav.world.model import World

AXES = "xyz"


def decode_text(data: bytes, source: str) -> str:
    """The bytes of a map file as text; one MapError if they are not UTF-8 text."""
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise MapError(source, f"not a UTF-8 text file (bad byte at offset {error.start})"
                       ) from None
    if "\x00" in text:
        raise MapError(source, "not a text file (contains NUL bytes)")
    return text


def keyword_lines(text: str, source: str, keywords: tuple[str, ...]
                  ) -> Iterator[tuple[int, str, list[str]]]:
    """``(line number, keyword, value fields)`` for each line of a keyword map text that
    holds anything once ``#`` comments are removed; MapError for an unknown keyword."""
    for number, raw in enumerate(text.splitlines(), start=1):
        fields = raw.split("#", 1)[0].split()
        if not fields:
            continue
        if fields[0] not in keywords:
            raise MapError(source, f"unknown keyword {fields[0]!r}: expected "
                           + " or ".join(repr(k) for k in keywords), number)
        yield number, fields[0], fields[1:]


def parse_float(token: str, source: str, line: int, what: str) -> float:
    """A finite float from a token such as ``3``, ``-0.5`` or ``2.000000``."""
    try:
        value = float(token)
    except ValueError:
        raise MapError(source, f"{what}: expected a number, got {token!r}", line) from None
    return check_finite(value, source, line, what)


def check_finite(value: float, source: str, line: int | None, what: str) -> float:
    """``value`` itself if it is finite; otherwise a MapError."""
    if not math.isfinite(value):
        raise MapError(source, f"{what}: expected a finite number, got {value!r}", line)
    return value


def check_box(box: Sequence[float], source: str, line: int | None, what: str) -> list[float]:
    """A box ``[xmin, ymin, zmin, xmax, ymax, zmax]`` whose mins are below its maxes."""
    for axis in range(3):
        if box[axis] >= box[axis + 3]:
            raise MapError(
                source,
                f"{what}: expected {AXES[axis]}min < {AXES[axis]}max, "
                f"got {box[axis]:g} >= {box[axis + 3]:g}",
                line,
            )
    return list(box)


def check_color(color: Sequence[float], scale: float, source: str, line: int | None,
                what: str) -> list[float]:
    """A colour in 0..scale (255 for text maps, 1 for JSON), returned in 0..1."""
    if any(not 0 <= c <= scale for c in color):
        raise MapError(source, f"{what}: expected colour values in 0..{scale:g}, got "
                       f"{' '.join(f'{c:g}' for c in color)}", line)
    return [c / scale for c in color]


def assemble_world(
    source: str,
    boundary: Sequence[float],
    blocks: Sequence[Sequence[float]],
    colors: Sequence[Sequence[float]],
    lines: Sequence[int | None],
    **extras: object,
) -> World:
    """A World from checked parts, clipping blocks to the boundary.

    A block partly outside the boundary is clipped to it; one wholly outside (or only
    touching it) is dropped. Each repair is reported as a :class:`MapWarning` naming
    the line. ``extras`` (start, goal, margin) pass through to the World.
    """
    bound = np.asarray(boundary, dtype=np.float64)
    kept_blocks, kept_colors = [], []
    for box, color, line in zip(blocks, colors, lines, strict=True):
        where = source if line is None else f"{source}:{line}"
        lower = np.maximum(box[:3], bound[:3])
        upper = np.minimum(box[3:], bound[3:])
        if np.any(lower >= upper):
            warnings.warn(f"{where}: block lies outside the boundary; dropped", MapWarning,
                          stacklevel=2)
            continue
        clipped = np.concatenate([lower, upper])
        if not np.array_equal(clipped, box):
            warnings.warn(f"{where}: block extends past the boundary; clipped to it",
                          MapWarning, stacklevel=2)
        kept_blocks.append(clipped)
        kept_colors.append(color)
    return World(
        boundary=bound,
        blocks=np.reshape(kept_blocks, (-1, 6)),
        colors=np.reshape(kept_colors, (-1, 3)),
        name=source,
        **extras,
    )
