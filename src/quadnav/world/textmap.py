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

from typing import Any

import numpy as np

from quadnav.errors import MapError
from quadnav.limits import MAX_BLOCKS, format_number
from quadnav.world.blockrows import BlockRows, order_rows
from quadnav.world.model import DEFAULT_BLOCK_COLOR, World
from quadnav.world.reading import (
    assemble_world,
    check_block_count,
    check_color,
    keyword_lines,
    parse_float,
    read_box,
    text_pieces,
)
from quadnav.world.textblocks import read_block_lines

_FIELD_COUNTS = (6, 9)
#: Characters of a map read at a time (about 4,500 block lines): what the numpy reading of
#: a piece holds besides the blocks.
PIECE_CHARACTERS = 1 << 18
#: Characters of the smaller pieces a piece with something to say is read in again: those
#: of them that still have something to say are read line by line.
SMALL_PIECE_CHARACTERS = 1 << 13
#: The colour of a block line that gives none, as a text map writes colours (0-255).
_NO_COLOR = [c * 255 for c in DEFAULT_BLOCK_COLOR]


def parse_text_map(text: str, source: str) -> World:
    """Parse the text of a map file; raises MapError naming ``source`` and the line.

    The file is read a piece of :data:`PIECE_CHARACTERS` at a time: a piece of plain block
    lines whose numbers are finite, colours in range and blocks within the count is read by
    numpy (:func:`~quadnav.world.textblocks.read_block_lines`), any other piece line by line
    by the checker, which says what is wrong; the blocks go into flat arrays either way."""
    reader = _TextMapReader(source)
    for piece, first_line in text_pieces(text, PIECE_CHARACTERS):
        if not reader.read_block_piece(piece, first_line):
            for small, small_first_line in text_pieces(piece, SMALL_PIECE_CHARACTERS):
                line = first_line + small_first_line - 1
                if not reader.read_block_piece(small, line):
                    reader.check_lines(small, line)
    return reader.world()


class _TextMapReader:
    """What a text map has said so far, as its pieces are read in order."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.boundary: list[float] | None = None
        self.boundary_line = 0
        self.blocks = BlockRows()
        self.saw_content = False

    def read_block_piece(self, piece: str, first_line: int) -> bool:
        """Read the whole lines of ``piece`` (the first numbered ``first_line``) with numpy
        if they are plain block lines whose numbers are finite, colours in range and blocks
        within the count; whether it did."""
        found = read_block_lines(piece, first_line, _NO_COLOR)
        if found is None:
            return False
        rows, lines = found
        if not (len(self.blocks) + len(rows) <= MAX_BLOCKS and np.all(np.isfinite(rows))
                and np.all((rows[:, 6:] >= 0) & (rows[:, 6:] <= 255))):
            return False
        self.blocks.extend(*order_rows(rows[:, :6], rows[:, 6:] / 255, lines, self.source,
                                       lambda _row: "block"))
        self.saw_content = self.saw_content or lines.size > 0
        return True

    def check_lines(self, piece: str, first_line: int) -> None:
        """Read the whole lines of ``piece`` (the first numbered ``first_line``) line by
        line, checking each number."""
        source = self.source
        for number, keyword, values in keyword_lines(piece, source, ("boundary", "block"),
                                                     first_line):
            self.saw_content = True
            if len(values) not in _FIELD_COUNTS:
                raise MapError(
                    source,
                    f"{keyword}: expected 6 numbers (xmin ymin zmin xmax ymax zmax) "
                    f"optionally followed by r g b, got {len(values)} fields",
                    number,
                )
            numbers = [parse_float(v, source, number, keyword) for v in values]
            color = check_color(numbers[6:] or _NO_COLOR, 255, source, number, keyword)
            if keyword == "boundary":
                if self.boundary is not None:
                    raise MapError(source, f"a second boundary line (the first is line "
                                   f"{self.boundary_line}): expected exactly one", number)
                self.boundary = read_box(numbers[:6], source, number, keyword, boundary=True)
                self.boundary_line = number
            else:
                check_block_count(len(self.blocks) + 1, source, number)
                box = read_box(numbers[:6], source, number, keyword)
                if box is not None:
                    self.blocks.add(box, color, number)

    def world(self) -> World:
        """The World of the whole map; MapError if it said nothing or has no boundary."""
        if not self.saw_content:
            raise MapError(self.source, "empty map: expected a 'boundary' line and 'block' lines")
        if self.boundary is None:
            raise MapError(self.source, "no 'boundary xmin ymin zmin xmax ymax zmax' line")
        return assemble_world(self.source, self.boundary, *self.blocks.arrays())


def format_text_map(world: World) -> str:
    """The world as a text map; reading it back gives the same numbers.

    The text format has no place for a start, goal or margin: they are written as
    comments, for a reader's eyes only.
    """
    def numbers(values: Any) -> list[str]:
        return [format_number(float(v), grouped=False) for v in values]

    out = [f"# {world.name}", "# boundary xmin ymin zmin xmax ymax zmax",
           "# block xmin ymin zmin xmax ymax zmax r g b (colour 0-255)"]
    for key in ("start", "goal"):
        value = getattr(world, key)
        if value is not None:
            out.append(f"# {key}: ({', '.join(numbers(value))})")
    if world.margin is not None:
        out.append(f"# margin: {numbers([world.margin])[0]}")
    out.append("boundary " + " ".join(numbers(world.boundary)))
    for box, color in zip(world.blocks, world.colors, strict=True):
        out.append("block " + " ".join(numbers([*box, *(color * 255)])))
    return "\n".join(out) + "\n"
