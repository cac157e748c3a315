"""The RBE595 / MEAM620 text map format.

::

    # comment
    boundary xmin ymin zmin xmax ymax zmax [r g b]
    block    xmin ymin zmin xmax ymax zmax [r g b]

Metres; colours 0-255. Accepted as found in the wild: blank lines, tabs, CRLF line
ends, ``#`` comments (whole-line or trailing), ``%f``-style numbers such as
``2.000000``, the boundary line anywhere (even after the blocks), a boundary line with
a colour (ignored), blocks without a colour, overlapping blocks, a min above its max
(read as the box between them, with a warning).
"""

from __future__ import annotations

from quadnav.errors import MapError
from quadnav.world.model import DEFAULT_BLOCK_COLOR, World
from quadnav.world.reading import (
    assemble_world,
    check_block_count,
    check_color,
    keyword_lines,
    parse_float,
    read_box,
)

_FIELD_COUNTS = (6, 9)


def parse_text_map(text: str, source: str) -> World:
    """Parse the text of a map file; raises MapError naming ``source`` and the line."""
    boundary: list[float] | None = None
    boundary_line = 0
    blocks: list[list[float]] = []
    colors: list[list[float]] = []
    lines: list[int] = []
    saw_content = False
    for number, keyword, values in keyword_lines(text, source, ("boundary", "block")):
        saw_content = True
        if len(values) not in _FIELD_COUNTS:
            raise MapError(
                source,
                f"{keyword}: expected 6 numbers (xmin ymin zmin xmax ymax zmax) "
                f"optionally followed by r g b, got {len(values)} fields",
                number,
            )
        numbers = [parse_float(v, source, number, keyword) for v in values]
        color = check_color(numbers[6:] or [c * 255 for c in DEFAULT_BLOCK_COLOR], 255,
                            source, number, keyword)
        if keyword == "boundary":
            if boundary is not None:
                raise MapError(source, f"a second boundary line (the first is line "
                               f"{boundary_line}): expected exactly one", number)
            boundary = read_box(numbers[:6], source, number, keyword, boundary=True)
            boundary_line = number
        else:
            check_block_count(len(blocks) + 1, source, number)
            box = read_box(numbers[:6], source, number, keyword)
            if box is not None:
                blocks.append(box)
                colors.append(color)
                lines.append(number)
    if not saw_content:
        raise MapError(source, "empty map: expected a 'boundary' line and 'block' lines")
    if boundary is None:
        raise MapError(source, "no 'boundary xmin ymin zmin xmax ymax zmax' line")
    return assemble_world(source, boundary, blocks, colors, lines)


def format_number(value: float) -> str:
    """The shortest text that reads back as exactly ``value`` (``3`` rather than ``3.0``)."""
    if value.is_integer() and abs(value) < 1e15:
        return str(int(value))
    return repr(value)


def format_text_map(world: World) -> str:
    """The world as a text map; reading it back gives the same numbers.

    The text format has no place for a start, goal or margin: they are written as
    comments, for a reader's eyes only.
    """
    out = [f"# {world.name}", "# boundary xmin ymin zmin xmax ymax zmax",
           "# block xmin ymin zmin xmax ymax zmax r g b (colour 0-255)"]
    for key in ("start", "goal"):
        value = getattr(world, key)
        if value is not None:
            out.append(f"# {key}: ({', '.join(format_number(float(v)) for v in value)})")
    if world.margin is not None:
        out.append(f"# margin: {format_number(world.margin)}")
    out.append("boundary " + " ".join(format_number(float(v)) for v in world.boundary))
    for box, color in zip(world.blocks, world.colors, strict=True):
        numbers = [*box, *(color * 255)]
        out.append("block " + " ".join(format_number(float(v)) for v in numbers))
    return "\n".join(out) + "\n"
