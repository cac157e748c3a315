"""The MEAM620 flightsim / rotorpy JSON map format.

::

    {"bounds": {"extents": [xmin, xmax, ymin, ymax, zmin, zmax]},
     "blocks": [{"extents": [...same interleaved order...], "color": [r, g, b]}],
     "start": [x, y, z], "goal": [x, y, z], "margin": 0.3}

Extents interleave min and max per axis; colours are 0-1 and optional; ``blocks``,
``start``, ``goal`` and ``margin`` are optional, other keys (``resolution``,
``expected_path_length``, ``timeout``, ...) are ignored. A min above its max is read as
the box between them, with a warning. Error messages name the line where the offending
JSON object begins.
"""

from __future__ import annotations

import json
import json.decoder
import json.scanner
import math
import re
import warnings
from collections.abc import Iterator
from typing import Any

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.errors import MapError, MapWarning
from quadnav.limits import format_number, is_number
from quadnav.world.blockrows import BlockRows, order_rows
from quadnav.world.jsonblocks import BlockTable
from quadnav.world.model import DEFAULT_BLOCK_COLOR, World
from quadnav.world.reading import (
    assemble_world,
    check_block_count,
    check_color,
    check_coordinates,
    check_finite,
    check_margin,
    read_box,
)


class _LocatedDict(dict):
    """A JSON object that remembers the line it starts on."""

    line: int


class _Literal(float):
    """A JSON number too large for a float that remembers how the file wrote it (to name it
    by its digits, not as ``inf``)."""

    __slots__ = ("text",)


class _RefusedError(ValueError):
    """What the decoder refuses that JSON itself allows: a message, and its line or the
    text whose first place in the file is its line."""

    def __init__(self, message: str, line: int | None = None, token: str = "") -> None:
        super().__init__(message)
        self.line = line
        self.token = token


def _read_number(text: str) -> float:
    """A JSON number's value (a :class:`_Literal` keeping its digits when it is too large
    for a float); :class:`_RefusedError` for one written with digits other than ASCII's
    (Python's pure-Python JSON scanner matches any Unicode digit)."""
    if not text.isascii():
        raise _RefusedError(f"expected a number in ASCII digits, got {text!r}", token=text)
    value = float(text)
    if math.isfinite(value):
        return value
    literal = _Literal(text)
    literal.text = text
    return literal


def _decode_with_lines(text: str, table: BlockTable) -> Any:
    """json.loads, but every object is a _LocatedDict carrying its 1-based line (or, shaped
    as a block, a row of ``table`` with its line), a key given twice in one object is
    refused (JSON leaves it open; Python keeps the last), and so is a number in other than
    ASCII digits."""
    # Integers become floats as they are read: every number in a map is used as one, and
    # int() refuses more than 4,300 digits.
    decoder = json.JSONDecoder(parse_int=_read_number, parse_float=_read_number)
    # Objects begin in the order they are read: count the newlines since the last one
    # (linear in the text, and nothing stored per line).
    cursor = {"offset": 0, "line": 1}

    def parse_object(s_and_end: tuple[str, int], strict: bool, scan_once: Any,
                     object_hook: Any, object_pairs_hook: Any, memo: Any = None
                     ) -> tuple[dict | int, int]:
        start = s_and_end[1]
        cursor["line"] += text.count("\n", cursor["offset"], start)
        cursor["offset"] = start
        line = cursor["line"]
        pairs, end = json.decoder.JSONObject(s_and_end, strict, scan_once, None, list, memo)
        row = table.compact(pairs, line)
        if row is not None:
            return row, end
        located = _LocatedDict(pairs)
        if len(located) < len(pairs):
            seen: set[str] = set()
            twice = next(key for key, _ in pairs if key in seen or seen.add(key))
            raise _RefusedError(f"key {json.dumps(twice)[:60]} given twice in one object: "
                           "expected each key once", line=line)
        located.line = line
        return located, end

    decoder.parse_object = parse_object  # type: ignore[assignment]
    decoder.scan_once = json.scanner.py_make_scanner(decoder)
    try:
        return decoder.decode(text)
    except _RefusedError as refused:
        if refused.line is None:
            refused.line = text.count("\n", 0, max(text.find(refused.token), 0)) + 1
        raise


def _line(obj: Any) -> int | None:
    return getattr(obj, "line", None)


def _number(value: Any, source: str, line: int | None, what: str) -> float:
    """``value`` as a finite float, or a MapError."""
    if not is_number(value):
        raise MapError(source, f"{what}: expected a number, got {json.dumps(value)[:60]}", line)
    return check_finite(float(value), source, line, what, getattr(value, "text", None))


def _numbers(value: Any, count: int, source: str, line: int | None, what: str) -> list[float]:
    """``value`` as a list of ``count`` finite numbers, or a MapError."""
    if not isinstance(value, list) or len(value) != count or not all(map(is_number, value)):
        raise MapError(source, f"{what}: expected a list of {count} numbers, got "
                       f"{json.dumps(value)[:60]}", line)
    return [_number(v, source, line, what) for v in value]


def _box(obj: Any, source: str, what: str, boundary: bool = False) -> list[float] | None:
    """The box of ``{"extents": [xmin, xmax, ymin, ymax, zmin, zmax]}`` as min/max rows
    (see :func:`~quadnav.world.reading.read_box`; ``None``: a dropped block)."""
    if not isinstance(obj, dict) or "extents" not in obj:
        raise MapError(source, f'{what}: expected an object with "extents"',
                       _line(obj))
    e = _numbers(obj["extents"], 6, source, _line(obj), f"{what}.extents")
    return read_box([e[0], e[2], e[4], e[1], e[3], e[5]], source, _line(obj), what, boundary)


def parse_json_map(text: str, source: str) -> World:
    """Parse the text of a JSON map; raises MapError naming ``source`` and the line.

    A map is read first by Python's compiled JSON decoder, which knows no lines; a map
    that reads cleanly (no error, no warning) is done. One with a warning is read again by
    it, each object given the line of its ``{`` (found by :func:`_object_lines`); one with
    an error is read again by the line-tracking decoder, which names the line of each
    object and the digits of a number beyond a float's range."""
    if not text or text.isspace():
        raise MapError(source, "empty map: expected a JSON object with \"bounds\"")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", MapWarning)
            world = _parse_compiled(text, source)
    except MapWarning:
        world = _parse_compiled(text, source, iter(_object_lines(text)))
        if world is None:
            # An error after the warnings (one the compiled decoder cannot name, such as a
            # number beyond a float's range): the warnings before it are said already.
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", MapWarning)
                return _parse_with_lines(text, source)
    return world if world is not None else _parse_with_lines(text, source)


#: A JSON string (skipped) or a brace (group 1).
_STRING_OR_BRACE = re.compile(r'"(?:[^"\\]|\\.)*"|([{}])')


def _object_lines(text: str) -> list[int]:
    """The 1-based line of each object's ``{`` in a JSON text (one that decodes), in the
    order the decoder finishes the objects (an object after those inside it)."""
    stack: list[int] = []
    starts: list[int] = []
    for match in _STRING_OR_BRACE.finditer(text):
        if match.group(1) == "{":
            stack.append(match.start())
        elif match.group(1) == "}":
            starts.append(stack.pop())
    lines = [0] * len(starts)
    line, offset = 1, 0
    for i in sorted(range(len(starts)), key=starts.__getitem__):
        line += text.count("\n", offset, starts[i])
        offset = starts[i]
        lines[i] = line
    return lines


def _parse_compiled(text: str, source: str, lines: Iterator[int] | None = None
                    ) -> World | None:
    """:func:`parse_json_map` by Python's compiled decoder, each object given the next of
    ``lines`` (in the order the decoder finishes them; ``None``: no lines); ``None`` if the
    map has an error."""
    table = BlockTable()

    def block_or_dict(pairs: list[tuple[str, Any]]) -> dict | int:
        """An object of the compiled decoder: a row of ``table`` if shaped as a block,
        else a dict; ValueError for a key given twice."""
        line = None if lines is None else next(lines)
        row = table.compact(pairs, line)
        if row is not None:
            return row
        data = _LocatedDict(pairs)
        if len(data) < len(pairs):
            raise ValueError("a key given twice")
        if line is not None:
            data.line = line
        return data

    try:
        data = json.loads(text, object_pairs_hook=block_or_dict, parse_int=float)
        return _interpret(data, source, table, dict if lines is None else _LocatedDict)
    except (ValueError, RecursionError, MapError):  # JSONDecodeError is a ValueError
        return None


def _parse_with_lines(text: str, source: str) -> World:
    """:func:`parse_json_map` by the line-tracking decoder."""
    table = BlockTable()
    try:
        data = _decode_with_lines(text, table)
    except json.JSONDecodeError as error:
        raise MapError(source, f"broken JSON: {error.msg} (column {error.colno})",
                       error.lineno) from None
    except _RefusedError as refused:
        raise MapError(source, str(refused), refused.line) from None
    except RecursionError:
        raise MapError(source, "broken JSON: nested too deeply") from None
    return _interpret(data, source, table, _LocatedDict)


def _interpret(data: Any, source: str, table: BlockTable, make_dict: type[dict] = dict
               ) -> World:
    """The World of a decoded JSON map (objects carry their line, or none; those shaped as
    blocks are rows of ``table``, given back as ``make_dict`` where a dict is needed)."""
    data = table.restore(data, make_dict) if type(data) is int else data
    if not isinstance(data, dict):
        raise MapError(source, "expected a JSON object at the top level", 1)
    if "bounds" not in data:
        raise MapError(source, 'missing key "bounds": expected {"bounds": {"extents": '
                       "[xmin, xmax, ymin, ymax, zmin, zmax]}}", _line(data))
    boundary = _box(table.restore(data["bounds"], make_dict), source, "bounds", boundary=True)
    raw_blocks = data.get("blocks", [])
    if not isinstance(raw_blocks, list):
        raise MapError(source, '"blocks": expected a list of objects', _line(data))
    check_block_count(len(raw_blocks), source, _line(data))
    extras = {key: table.restore(data[key], make_dict) for key in ("start", "goal", "margin")
              if key in data}
    done, plain = _plain_blocks(raw_blocks, 0, table, source)
    if done < len(raw_blocks):
        blocks = BlockRows()
        blocks.extend(*plain)
        while done < len(raw_blocks):
            obj = table.restore(raw_blocks[done], make_dict)
            box = _box(obj, source, f"blocks[{done}]")
            rgb = _numbers(obj.get("color", list(DEFAULT_BLOCK_COLOR)), 3, source, _line(obj),
                           f"blocks[{done}].color")
            color = check_color(rgb, 1.0, source, _line(obj), f"blocks[{done}].color")
            if box is not None:
                blocks.add(box, color, _line(obj))
            done, plain = _plain_blocks(raw_blocks, done + 1, table, source)
            blocks.extend(*plain)
        plain = blocks.arrays()
    table.clear()
    for key in ("start", "goal"):
        if key in extras:
            point = _numbers(extras[key], 3, source, _line(data), key)
            extras[key] = check_coordinates(point, source, _line(data), key)
    if "margin" in extras:
        extras["margin"] = check_margin(_number(extras["margin"], source, _line(data),
                                                "margin"), source, _line(data))
    return assemble_world(source, boundary, *plain, **extras)


def _plain_blocks(raw_blocks: list[Any], start: int, table: BlockTable, source: str
                  ) -> tuple[int, tuple[FloatArray, FloatArray, np.ndarray]]:
    """The entries of ``raw_blocks`` from ``start`` on that are rows of ``table`` with
    finite numbers and colours in 0..1, read all at once: the index of the first entry after
    them, and their boxes (mins then maxes), colours and lines (see
    :func:`~quadnav.world.blockrows.order_rows`). That entry (if any) is to be read on its
    own: it says what is wrong with it, or is fine in a way that is not a row's."""
    end = next((i for i in range(start, len(raw_blocks)) if type(raw_blocks[i]) is not int),
               len(raw_blocks))
    boxes, colors, colored, lines = table.rows(np.array(raw_blocks[start:end],
                                                        dtype=np.int64))
    colors[~colored] = DEFAULT_BLOCK_COLOR
    fine = np.all(np.isfinite(boxes), axis=1) & np.all(
        np.isfinite(colors) & (colors >= 0) & (colors <= 1), axis=1)
    if not fine.all():
        count = int(np.argmin(fine))
        boxes, colors, lines = boxes[:count], colors[:count], lines[:count]
        end = start + count
    return end, order_rows(boxes, colors, lines, source, lambda row: f"blocks[{start + row}]")


def _json_list(values: Any) -> str:
    return "[" + ", ".join(format_number(float(v), grouped=False) for v in values) + "]"


def _interleaved(box: Any) -> str:
    return _json_list([box[0], box[3], box[1], box[4], box[2], box[5]])


def format_json_map(world: World) -> str:
    """The world as a JSON map (one block per line); reading it back gives the same numbers."""
    out = ["{", f'    "bounds": {{"extents": {_interleaved(world.boundary)}}},']
    blocks = [f'        {{"extents": {_interleaved(box)}, "color": {_json_list(color)}}}'
              for box, color in zip(world.blocks, world.colors, strict=True)]
    out.append('    "blocks": [' + ("\n" + ",\n".join(blocks) + "\n    " if blocks else "") + "]")
    for key in ("start", "goal"):
        value = getattr(world, key)
        if value is not None:
            out[-1] += ","
            out.append(f'    "{key}": {_json_list(value)}')
    if world.margin is not None:
        out[-1] += ","
        out.append(f'    "margin": {format_number(world.margin, grouped=False)}')
    out.append("}")
    return "\n".join(out) + "\n"
