"""Checks shared by the map readers: numbers, boxes, and assembling a :class:`World`.

Every problem is raised as :class:`~quadnav.errors.MapError` naming the source and
line; repairs (clipping a block to the boundary, dropping one outside it) are
reported as :class:`~quadnav.errors.MapWarning`.
"""

from __future__ import annotations

import math
import re
import warnings
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.errors import MapError, MapWarning
from quadnav.inputfiles import not_a_file, special_file
from quadnav.limits import (
    BOUNDARY_SIDE,
    COORDINATE,
    MARGIN,
    MAX_BLOCKS,
    MAX_FILE_BYTES,
    MAX_LINE,
    format_number,
)
from quadnav.world.model import World

AXES = "xyz"

#: A line end of a text file: ``\n``, ``\r\n`` or ``\r``, and nothing else (``str.splitlines``
#: also ends lines at a form feed, a vertical tab, U+0085, U+2028, ..., which would end a ``#``
#: comment inside a line and read the rest of it).
_LINE_END = re.compile(r"\r\n|\r|\n")
#: A number as a map file may write it: ASCII digits with an optional sign, point and exponent,
#: or ``inf``/``nan`` (refused as not finite). Python's ``float`` also takes ``1_000`` and
#: non-ASCII digits; a map does not.
_NUMBER = re.compile(r"[+-]?(?:(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|inf|infinity|nan)",
                     re.ASCII | re.IGNORECASE)
#: Characters of a number's text shown in a message before it is cut.
_SHOWN = 24


def read_file(path: str | Path) -> bytes:
    """The bytes of a map, start/goal, path or reference file; MapError if it cannot be read or is
    over :data:`~quadnav.limits.MAX_FILE_BYTES`."""
    kind = special_file(path)
    if kind is not None:
        raise MapError(str(path), not_a_file(kind, "a file"))
    try:
        with Path(path).open("rb") as file:
            data = file.read(MAX_FILE_BYTES + 1)
    except OSError as error:
        raise MapError(str(path), f"cannot read: {error.strerror}") from None
    _check_size(len(data), str(path))
    return data


def _check_size(size: int, source: str) -> None:
    if size > MAX_FILE_BYTES:
        raise MapError(source, f"the file is over {MAX_FILE_BYTES // 2**20} MiB: expected "
                       "a smaller map, start/goal, path or reference file")


def decode_text(data: bytes, source: str) -> str:
    """The bytes of a map file as text; one MapError if they are not UTF-8 text."""
    _check_size(len(data), source)
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise MapError(source, f"not a UTF-8 text file (bad byte at offset {error.start})"
                       ) from None
    if "\x00" in text:
        raise MapError(source, "not a text file (contains NUL bytes)")
    return text


def text_lines(text: str) -> list[str]:
    """The lines of a text file, split at its line ends (``\n``, ``\r\n``, ``\r``) only."""
    return _LINE_END.split(text)


def iter_text_lines(text: str) -> Iterator[str]:
    """The lines of :func:`text_lines` one at a time (no list of them all)."""
    start = 0
    for end in _LINE_END.finditer(text):
        yield text[start:end.start()]
        start = end.end()
    yield text[start:]


def text_pieces(text: str, size: int) -> Iterator[tuple[str, int]]:
    """``text`` in pieces of whole lines, each about ``size`` characters (more when a line
    is longer), with the 1-based number of each piece's first line; a piece ends just
    after a line end (``\r\n`` kept whole), the last one at the end of the text."""
    start, first_line = 0, 1
    while start < len(text):
        end = _LINE_END.search(text, start + size) if start + size < len(text) else None
        stop = len(text) if end is None else end.end()
        piece = text[start:stop]
        yield piece, first_line
        first_line += piece.count("\n") + piece.count("\r") - piece.count("\r\n")
        start = stop


def keyword_lines(text: str, source: str, keywords: tuple[str, ...], first_line: int = 1
                  ) -> Iterator[tuple[int, str, list[str]]]:
    """``(line number, keyword, value fields)`` for each line of a keyword map text that
    holds anything once ``#`` comments are removed; MapError for an unknown keyword.
    ``first_line``: the number of the text's first line (when it is a piece of a file)."""
    for number, raw in enumerate(iter_text_lines(text), start=first_line):
        check_line_length(raw, source, number)
        fields = raw.split("#", 1)[0].split()
        if not fields:
            continue
        if fields[0] not in keywords:
            raise MapError(source, f"unknown keyword {shown_text(fields[0])!r}: expected "
                           + " or ".join(repr(k) for k in keywords), number)
        yield number, fields[0], fields[1:]


def check_line_length(line: str, source: str, number: int) -> None:
    """MapError for a line longer than :data:`~quadnav.limits.MAX_LINE` characters."""
    if len(line) > MAX_LINE:
        raise MapError(source, f"line of {len(line):,} characters: expected at most "
                       f"{MAX_LINE:,}", number)


def is_number_text(token: str) -> bool:
    """Whether ``token`` is a number as a map writes it (ASCII digits, sign, point,
    exponent; or ``inf``/``nan``), not merely something ``float`` accepts."""
    return _NUMBER.fullmatch(token) is not None


def parse_float(token: str, source: str, line: int, what: str) -> float:
    """A finite float from a token such as ``3``, ``-0.5`` or ``2.000000``."""
    if not is_number_text(token):
        raise MapError(source, f"{what}: expected a number, got {shown_text(token)!r}", line)
    return check_finite(float(token), source, line, what, token)


def shown_text(text: str) -> str:
    """``text`` as a message shows it: whole, or its start and end around an ellipsis with
    its length when it is longer than a message line should be."""
    if len(text) <= _SHOWN:
        return text
    return f"{text[:_SHOWN // 2]}...{text[-4:]} ({len(text):,} characters)"


def check_finite(value: float, source: str, line: int | None, what: str,
                 text: str | None = None) -> float:
    """``value`` itself if it is finite; otherwise a MapError. ``text``: the number as the
    file writes it, named in the message when it is too large for a 64-bit float (such as
    a 5,000-digit integer) rather than calling it ``inf``."""
    if not math.isfinite(value):
        if text is not None and text.lstrip("+-").lower() not in ("inf", "infinity", "nan"):
            raise MapError(source, f"{what}: expected a finite number, got {shown_text(text)}"
                           ", beyond the largest a 64-bit float holds (1.8e308)", line)
        raise MapError(source, f"{what}: expected a finite number, got {value!r}", line)
    return value


def _where(source: str, line: int | None) -> str:
    return source if line is None else f"{source}:{line}"


def read_box(box: Sequence[float], source: str, line: int | None, what: str,
             boundary: bool = False) -> list[float] | None:
    """A box ``[xmin, ymin, zmin, xmax, ymax, zmax]`` from the numbers a map gives.

    A min above its max on an axis (found in real course files) is read as the box
    between the two values, with a :class:`MapWarning` naming the source and line. A
    block of zero thickness on an axis is dropped with a warning (``None``); a boundary
    of zero thickness, one with a side below :data:`~quadnav.limits.BOUNDARY_SIDE`, or
    one with a coordinate outside :data:`~quadnav.limits.COORDINATE` is a MapError.
    Block coordinates may be any finite numbers: blocks are clipped to the boundary.
    """
    ordered = order_extents(box, source, line, what, boundary)
    if ordered is None:
        return None
    lower, upper = ordered
    if boundary:
        check_coordinates(lower + upper, source, line, what)
        for a in range(3):
            if upper[a] - lower[a] not in BOUNDARY_SIDE:
                raise MapError(source, f"{what}: the boundary is {upper[a] - lower[a]:g} m "
                               f"along {AXES[a]}: expected sides {BOUNDARY_SIDE.describe()}",
                               line)
    return lower + upper


def order_extents(box: Sequence[float], source: str, line: int | None, what: str,
                  boundary: bool = False) -> tuple[list[float], list[float]] | None:
    """The lower and upper corners of a box given as its mins then its maxes (2 or 3 axes:
    ``[xmin, ymin, (zmin,) xmax, ymax, (zmax)]``): the one rule of every map format.

    A min above its max on an axis (found in real course files) is read as the box between
    the two values, with a :class:`MapWarning` naming the source and line. A block of zero
    thickness on an axis is dropped with a warning (``None``); a boundary of zero thickness
    is a MapError.
    """
    axes = len(box) // 2
    lower = [min(box[a], box[a + axes]) for a in range(axes)]
    upper = [max(box[a], box[a + axes]) for a in range(axes)]
    swapped = [a for a in range(axes) if box[a] > box[a + axes]]
    if swapped:
        details = ", ".join(f"{AXES[a]}min {box[a]:g} > {AXES[a]}max {box[a + axes]:g}"
                            for a in swapped)
        warnings.warn(f"{_where(source, line)}: {what}: min and max swapped ({details}); "
                      "read as the box between them", MapWarning, stacklevel=3)
    flat = [a for a in range(axes) if lower[a] == upper[a]]
    if flat:
        axis = AXES[flat[0]]
        thickness = f"zero thickness along {axis} ({axis}min = {axis}max = {lower[flat[0]]:g})"
        if boundary:
            raise MapError(source, f"{what}: {thickness}: expected a box with a volume", line)
        warnings.warn(f"{_where(source, line)}: {what}: {thickness}; dropped", MapWarning,
                      stacklevel=3)
        return None
    return lower, upper


def check_coordinates(values: Sequence[float], source: str, line: int | None,
                      what: str) -> list[float]:
    """``values`` (e.g. a start or goal ``[x, y, z]``) if every one is in
    :data:`~quadnav.limits.COORDINATE`; otherwise a MapError."""
    for value in values:
        if value not in COORDINATE:
            raise MapError(source, f"{what}: expected coordinates {COORDINATE.describe()}, "
                           f"got {format_number(value)}", line)
    return list(values)


def check_margin(value: float, source: str, line: int | None) -> float:
    """A map's margin, metres, in :data:`MARGIN`."""
    if value not in MARGIN:
        raise MapError(source, f"margin: expected {MARGIN.describe()}, got "
                       f"{format_number(value)}", line)
    return value


def check_block_count(count: int, source: str, line: int | None) -> None:
    """MapError once a map has more than :data:`MAX_BLOCKS` blocks."""
    if count > MAX_BLOCKS:
        raise MapError(source, f"more than {MAX_BLOCKS:,} blocks: expected at most "
                       f"{MAX_BLOCKS:,}", line)


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
    blocks: FloatArray,
    colors: FloatArray,
    lines: np.ndarray,
    **extras: object,
) -> World:
    """A World from checked parts, clipping blocks to the boundary.

    ``blocks`` (N, 6) as mins then maxes, ``colors`` (N, 3) in 0..1, ``lines`` (N,) the
    1-based line of each block (0: none known). A block partly outside the boundary is
    clipped to it; one wholly outside (or only touching it) is dropped. Each repair is
    reported as a :class:`MapWarning` naming the line, in the order of the blocks.
    ``extras`` (start, goal, margin) pass through to the World.
    """
    bound = np.asarray(boundary, dtype=np.float64)
    past = np.flatnonzero(np.any(blocks[:, :3] < bound[:3], axis=1)
                          | np.any(blocks[:, 3:] > bound[3:], axis=1))
    if past.size:
        lower = np.maximum(blocks[past, :3], bound[:3])
        upper = np.minimum(blocks[past, 3:], bound[3:])
        outside = np.any(lower >= upper, axis=1)
        for row, dropped in zip(past.tolist(), outside.tolist(), strict=True):
            where = _where(source, int(lines[row]) or None)
            if dropped:
                warnings.warn(f"{where}: block lies outside the boundary; dropped",
                              MapWarning, stacklevel=2)
            else:
                warnings.warn(f"{where}: block extends past the boundary; clipped to it",
                              MapWarning, stacklevel=2)
        blocks = blocks.copy()
        blocks[past] = np.concatenate([lower, upper], axis=1)
        kept = np.ones(len(blocks), dtype=bool)
        kept[past[outside]] = False
        blocks, colors = blocks[kept], colors[kept]
    return World(boundary=bound, blocks=blocks, colors=colors, name=source, **extras)
