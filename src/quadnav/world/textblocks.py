"""The ``block`` lines of a text map read with numpy, a piece of the file at a time.

:func:`read_block_lines` takes a piece of whole lines and gives its blocks' numbers when every
line is blank or a ``block`` line whose 6 or 9 fields are numbers as a map writes them (see
:func:`~quadnav.world.reading.is_number_text`), separated by spaces or tabs, with ``\\n`` or
``\\r\\n`` line ends and ASCII ``#`` comments; otherwise ``None``, and the piece is read line
by line by the checker of :mod:`quadnav.world.textmap`, which says what is wrong. Numbers are
converted by numpy's parser, which rounds as Python's ``float`` does; that they are finite and
in range is left to the caller.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.limits import MAX_LINE

_KEYWORD = b"block"

#: Byte classes: a separator (space, tab, line end), a digit, a point, a sign, an exponent
#: letter, a letter of the keyword; any other byte is :data:`_OTHER`.
_SPACE, _DIGIT, _POINT, _SIGN, _EXPONENT, _LETTER, _OTHER = range(7)
_CLASS = np.full(256, _OTHER, dtype=np.uint8)
for _chars, _kind in ((b" \t\r\n", _SPACE), (b"0123456789", _DIGIT), (b".", _POINT),
                      (b"+-", _SIGN), (b"eE", _EXPONENT), (_KEYWORD, _LETTER)):
    _CLASS[list(_chars)] = _kind


def _valid_triples() -> np.ndarray:
    """Whether a byte of each class may stand between each previous and next class in a
    number ``[+-]? (digits [. digits] | . digits) ([eE] [+-]? digits)?`` (one point and one
    exponent a number, the point first, are checked apart), indexed ``prev*49 + this*7 + next``."""
    valid = np.zeros(7 * 7 * 7, dtype=bool)
    for before in range(7):
        for after in range(7):
            rules = {
                _SPACE: True,
                _DIGIT: True,
                _SIGN: (before == _SPACE and after in (_DIGIT, _POINT))
                or (before == _EXPONENT and after == _DIGIT),
                _POINT: (before == _DIGIT and after in (_DIGIT, _EXPONENT, _SPACE))
                or (before in (_SPACE, _SIGN) and after == _DIGIT),
                _EXPONENT: before in (_DIGIT, _POINT) and after in (_DIGIT, _SIGN),
            }
            for this, ok in rules.items():
                valid[before * 49 + this * 7 + after] = ok
    return valid


_VALID = _valid_triples()


def read_block_lines(piece: str, first_line: int, no_color: Sequence[float]
                     ) -> tuple[FloatArray, np.ndarray] | None:
    """The numbers of the ``block`` lines of ``piece`` (whole lines of a text map, the
    first numbered ``first_line``) as rows (k, 9) ``xmin ymin zmin xmax ymax zmax r g b``
    (``no_color`` where a line gives none), and the line of each row (k,); ``None`` when a
    line is anything else (a boundary line, a lone ``\\r``, a word that is not a number, a line
    longer than :data:`~quadnav.limits.MAX_LINE`, ...). ``#`` comments are read as spaces."""
    if not piece.isascii():
        return None
    text = np.frombuffer(bytearray(piece, "ascii"), dtype=np.uint8)
    returns = np.flatnonzero(text == ord("\r"))
    if returns.size and (returns[-1] + 1 == text.size or np.any(text[returns + 1] != 10)):
        return None
    ends = np.flatnonzero(text == ord("\n"))
    if np.diff(ends, prepend=-1, append=text.size).max(initial=0) > MAX_LINE:
        return None
    _blank_comments(text, ends)
    kinds = _CLASS[text]
    if np.any(kinds == _OTHER):
        return None
    words, word_ends = _words(kinds)
    line_of = np.searchsorted(ends, words)
    first = np.ones(words.size, dtype=bool)
    first[1:] = line_of[1:] != line_of[:-1]
    keywords = words[first]
    if (np.any(word_ends[first] - keywords != len(_KEYWORD))
            or np.count_nonzero(kinds == _LETTER) != len(_KEYWORD) * keywords.size
            or any(np.any(text[keywords + i] != c) for i, c in enumerate(_KEYWORD))):
        return None
    fields = np.diff(np.flatnonzero(np.append(first, True))) - 1
    if not np.all((fields == 6) | (fields == 9)):
        return None
    blanked = keywords[:, None] + np.arange(len(_KEYWORD))
    kinds[blanked] = _SPACE
    if not _numbers_well_formed(kinds, words[~first]):
        return None
    text[blanked] = ord(" ")
    values = np.fromstring(text.tobytes(), sep=" ")
    if values.size != fields.sum():
        return None
    return _rows(values, fields, no_color), first_line + line_of[first]


def _blank_comments(text: np.ndarray, ends: np.ndarray) -> None:
    """Turn every ``#`` comment of ``text`` (from a ``#`` to the end of its line, whose
    ``\n`` are at ``ends``) into spaces, in place."""
    hashes = np.flatnonzero(text == ord("#"))
    if hashes.size == 0:
        return
    stops = np.append(ends, text.size)[np.searchsorted(ends, hashes)]
    depth = np.zeros(text.size + 1, dtype=np.int32)
    np.add.at(depth, hashes, 1)
    np.add.at(depth, stops, -1)
    text[np.cumsum(depth[:-1]) > 0] = ord(" ")


def _words(kinds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where each word (a run of bytes that are not separators) starts and ends."""
    inside = np.zeros(kinds.size + 2, dtype=np.int8)
    inside[1:-1] = kinds != _SPACE
    edges = np.diff(inside)
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def _numbers_well_formed(kinds: np.ndarray, starts: np.ndarray) -> bool:
    """Whether every word (starting at ``starts``) in ``kinds`` (keywords blanked to
    separators) is a number as a map writes it."""
    padded = np.full(kinds.size + 2, _SPACE, dtype=np.uint16)
    padded[1:-1] = kinds
    triples = padded[:-2] * 49 + padded[1:-1] * 7 + padded[2:]
    if not np.all(_VALID[triples]):
        return False
    points = np.flatnonzero(kinds == _POINT)
    exponents = np.flatnonzero(kinds == _EXPONENT)
    point_word = np.searchsorted(starts, points, side="right")
    exponent_word = np.searchsorted(starts, exponents, side="right")
    if np.any(point_word[1:] == point_word[:-1]) or np.any(
            exponent_word[1:] == exponent_word[:-1]):
        return False
    next_point = np.searchsorted(points, exponents)
    later = next_point < points.size
    return not np.any(point_word[next_point[later]] == exponent_word[later])


def _rows(values: FloatArray, fields: np.ndarray, no_color: Sequence[float]) -> FloatArray:
    """``values`` laid out as rows of 9, a row of 6 numbers given ``no_color``."""
    if np.all(fields == 9):
        return values.reshape(-1, 9)
    rows = np.empty((fields.size, 9))
    rows[:, 6:] = no_color
    starts = np.cumsum(fields) - fields
    for column in range(9):
        given = fields > column
        rows[given, column] = values[starts[given] + column]
    return rows
