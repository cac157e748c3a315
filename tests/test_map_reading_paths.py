"""The fast ways of reading a map give what the checker gives, and reading is lean.

A text map's plain block lines are read with numpy (world/textblocks.py) and a JSON map's
block objects become rows of flat arrays as they are decoded (world/jsonblocks.py); anything
else is read by the checker one line or object at a time. Each fast path is compared with the
checker alone, on the public course maps and on generated maps with every quirk the fast
path hands over (comments, CRLF and lone CR, tabs, missing colours, extra fields, swapped and
flat blocks, bad numbers and keywords, long lines, a boundary anywhere, ...): same arrays to
the bit, same warnings, same errors.
"""

from __future__ import annotations

import json
import random
import tracemalloc
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from quadnav.errors import MapError
from quadnav.world import jsonmap, parse_map, textmap
from quadnav.world.jsonblocks import BlockTable
from quadnav.world.reading import is_number_text
from quadnav.world.textblocks import read_block_lines

GOOD_NUMBERS = ["1", "-2.5", "3.", ".5", "+4", "1e1", "2.5E-1", "-.5e+1", "0", "007", "1e-3"]
BAD_NUMBERS = ["1e", "1-2", ".", "1_000", "inf", "nan", "1e400", "\u0663", "e5", "--1", "1..2",
               "1e5.5", "x", "+", "1e+", "-.", ".e5", "1ee5", "1,5", "0x10", "9" * 400]
QUIRKS = ["swap", "flat", "nocolor", "badcolor", "bad", "extra", "tabs", "lead", "trail",
          "comment", "keyword", "crlf", "cr", "blank", "boundary_mid", "second_boundary",
          "unicode_space", "long", "outside"]


def _number(rng: random.Random, value: float) -> str:
    kind = rng.random()
    if kind < 0.5:
        return f"{value:.3f}"
    if kind < 0.7:
        return repr(value)
    if kind < 0.8:
        return f"{value:e}"
    return rng.choice(GOOD_NUMBERS)


def _block_line(rng: random.Random, quirks: set[str]) -> str:
    low = [rng.uniform(-2, 18), rng.uniform(-2, 18), rng.uniform(-1, 5)]
    high = [v + rng.uniform(0.1, 3) for v in low]
    if "outside" in quirks and rng.random() < 0.05:
        low[0], high[0] = 30.0, 31.0
    words = [_number(rng, v) for v in low + high]
    if "swap" in quirks and rng.random() < 0.1:
        axis = rng.randrange(3)
        words[axis], words[axis + 3] = words[axis + 3], words[axis]
    if "flat" in quirks and rng.random() < 0.05:
        axis = rng.randrange(3)
        words[axis + 3] = words[axis]
    if not ("nocolor" in quirks and rng.random() < 0.5):
        words += [str(rng.randint(0, 255)) for _ in range(3)]
    if "badcolor" in quirks and rng.random() < 0.01:
        words[-1] = "256"
    if "bad" in quirks and rng.random() < 0.01:
        words[rng.randrange(len(words))] = rng.choice(BAD_NUMBERS)
    if "extra" in quirks and rng.random() < 0.01:
        words.append("1")
    space = rng.choice([" ", "\t", "  ", " \t "]) if "tabs" in quirks else " "
    line = "block" + space + space.join(words)
    if "lead" in quirks and rng.random() < 0.1:
        line = rng.choice([" ", "\t"]) + line
    if "trail" in quirks and rng.random() < 0.1:
        line += rng.choice([" ", "\t "])
    if "comment" in quirks and rng.random() < 0.05:
        line += rng.choice([" # c", "#x", " # n\x0cblock 1 1 0 9 9 5", "# \u00fc"])
    if "keyword" in quirks and rng.random() < 0.005:
        line = line.replace("block", rng.choice(["BLOCK", "blocks", "block1"]), 1)
    if "unicode_space" in quirks and rng.random() < 0.005:
        line = line.replace(" ", rng.choice(["\x0c", "\xa0", "\u2028"]), 1)
    return line


def quirky_text_map(seed: int) -> str:
    """A text map of a few hundred lines with a random set of quirks."""
    rng = random.Random(seed)
    quirks = {q for q in QUIRKS if rng.random() < 0.2}
    lines = [_block_line(rng, quirks) for _ in range(rng.choice([0, 3, 40, 300]))]
    if "blank" in quirks:
        for _ in range(len(lines) // 10 + 1):
            lines.insert(rng.randrange(len(lines) + 1), rng.choice(["", " ", "\t", " # c"]))
    boundary = "boundary 0 0 0 15 15 " + rng.choice(["5", "4.5", "1e1"])
    lines.insert(rng.randrange(len(lines) + 1) if "boundary_mid" in quirks else 0, boundary)
    if "second_boundary" in quirks:
        lines.insert(rng.randrange(len(lines) + 1), boundary)
    if "long" in quirks:
        lines[rng.randrange(len(lines))] += " " * rng.choice([9_990, 10_001])
    if rng.random() < 0.5:
        lines.insert(0, "# quirks: " + " ".join(sorted(quirks)))
    end = "\r\n" if "crlf" in quirks else "\n"
    text = end.join(lines) + rng.choice([end, ""])
    if "cr" in quirks:
        text = text.replace("\n", "\r", rng.randint(1, 3))
    return text


def quirky_json_map(seed: int) -> str:
    """A JSON map of up to a few hundred blocks with a random set of quirks."""
    rng = random.Random(seed)
    quirks = {q for q in ["swap", "flat", "nocolor", "badcolor", "nan", "extra", "order",
                          "other", "outside", "start", "bool", "nested", "huge", "dup", "strings"]
              if rng.random() < 0.12}
    blocks: list = []
    for _ in range(rng.choice([0, 3, 40, 300])):
        low = [rng.uniform(-2, 18), rng.uniform(-2, 18), rng.uniform(-1, 5)]
        extents = [v for a in low for v in (a, a + rng.uniform(0.1, 3))]
        if "swap" in quirks and rng.random() < 0.1:
            extents[0], extents[1] = extents[1], extents[0]
        if "flat" in quirks and rng.random() < 0.05:
            extents[3] = extents[2]
        if "nan" in quirks and rng.random() < 0.02:
            extents[rng.randrange(6)] = float(rng.choice(["nan", "inf"]))
        if "bool" in quirks and rng.random() < 0.02:
            extents[0] = True
        block: dict = {"extents": extents}
        if not ("nocolor" in quirks and rng.random() < 0.5):
            block["color"] = [rng.random() for _ in range(3)]
        if "badcolor" in quirks and rng.random() < 0.02:
            block["color"] = [1.5, 0, 0]
        if "extra" in quirks and rng.random() < 0.02:
            block["name"] = "x"
        if "order" in quirks and "color" in block and rng.random() < 0.1:
            block = {"color": block["color"], "extents": extents}
        if "other" in quirks and rng.random() < 0.01:
            block = rng.choice([3, "x", {"extent": extents}, {"extents": extents[:5]}, None])
        if "nested" in quirks and rng.random() < 0.01:
            block = [block]
        blocks.append(block)
    data: dict = {"bounds": {"extents": [0, 15, 0, 15, 0, rng.choice([5, 4.5, 10, 0])]},
                  "blocks": blocks}
    if "outside" in quirks:
        blocks.append({"extents": [20, 21, 20, 21, 0, 1]})
    if "start" in quirks:
        data["start"] = rng.choice([[1, 1, 1], {"extents": [1, 2, 3, 4, 5, 6]}, [1e5, 0, 0]])
        data["margin"] = rng.choice([0.3, -1, {"extents": [1, 2, 3, 4, 5, 6]}])
    if "strings" in quirks:  # braces and quotes in strings, objects within objects
        data["note {"] = 'a { b " } \\ {\n'
        data["other"] = {"x": {"extents": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]}, "y": "}"}
    text = json.dumps(data, indent=rng.choice([None, 1, 4]))
    if "huge" in quirks:
        text = text.replace('"extents": [', '"extents": [' + "9" * 400 + ", ", 1)
    if "dup" in quirks:
        text = text.replace('"color"', '"color": 1, "color"', 1)
    return text


def _outcome(data: bytes, name: str) -> tuple:
    """What reading ``data`` gives: the World's arrays (with the sign of each zero), or
    the error; and the warnings."""
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        try:
            world = parse_map(data, name)
        except MapError as error:
            result: tuple = ("error", str(error))
        else:
            result = tuple((a.tolist(), np.signbit(a).tolist()) for a in
                           (world.boundary, world.blocks, world.colors))
            result += tuple(None if v is None else np.asarray(v).tolist()
                            for v in (world.start, world.goal, world.margin))
    return result, [str(w.message) for w in said]


def _checker_alone(monkeypatch: pytest.MonkeyPatch) -> None:
    """Read every text line and every JSON object by the checker, one at a time (JSON by
    the line-tracking decoder alone)."""
    monkeypatch.setattr(textmap, "read_block_lines", lambda *args: None)
    monkeypatch.setattr(BlockTable, "compact", lambda self, pairs, line: None)
    monkeypatch.setattr(jsonmap, "_parse_compiled", lambda *args: None)


def _corpus_maps(shared_maps: Path | None) -> list[tuple[str, bytes]]:
    if shared_maps is None:
        return []
    return [(str(p), p.read_bytes()) for p in sorted(shared_maps.rglob("*"))
            if p.suffix in (".txt", ".json") and p.name != "SOURCES.json"]


def test_fast_text_reading_is_the_checker_s(monkeypatch, optional_shared_maps):
    maps = [(f"quirky{seed}.txt", quirky_text_map(seed).encode()) for seed in range(80)]
    maps += [(name, data) for name, data in _corpus_maps(optional_shared_maps)
             if name.endswith(".txt")]
    fast = [_outcome(data, name) for name, data in maps]
    with monkeypatch.context() as patch:
        # Pieces of a few lines: every quirk lands on a piece's edge somewhere.
        patch.setattr(textmap, "PIECE_CHARACTERS", 400)
        patch.setattr(textmap, "SMALL_PIECE_CHARACTERS", 90)
        small_pieces = [_outcome(data, name) for name, data in maps]
    _checker_alone(monkeypatch)
    checked = [_outcome(data, name) for name, data in maps]
    assert fast == checked
    assert small_pieces == checked
    # The generated maps are not all refused: most read, many with warnings.
    read = [said for (result, said) in checked if result[0] != "error"]
    assert len(read) > 30 and sum(bool(said) for said in read) > 10


def test_fast_json_reading_is_the_checker_s(monkeypatch, optional_shared_maps):
    maps = [(f"quirky{seed}.json", quirky_json_map(seed).encode()) for seed in range(80)]
    maps += [(name, data) for name, data in _corpus_maps(optional_shared_maps)
             if name.endswith(".json")]
    fast = [_outcome(data, name) for name, data in maps]
    _checker_alone(monkeypatch)
    checked = [_outcome(data, name) for name, data in maps]
    assert fast == checked
    read = [said for (result, said) in checked if result[0] != "error"]
    assert len(read) > 30 and sum(bool(said) for said in read) > 10


@settings(max_examples=300, deadline=None)
@given(st.lists(st.text("0123456789.+-eE", min_size=1, max_size=6)
                | st.sampled_from(GOOD_NUMBERS + BAD_NUMBERS), min_size=9, max_size=9))
def test_numpy_reads_a_word_as_a_number_exactly_when_the_checker_does(words):
    found = read_block_lines("block " + " ".join(words) + "\n", 1, [0.0, 0.0, 0.0])
    plain = all(is_number_text(w) and float(w) == float(w) and abs(float(w)) != float("inf")
                for w in words)
    if plain:
        assert found is not None
        assert found[0][0].tolist() == [float(w) for w in words]
    elif found is not None:  # taken by numpy, then refused by the caller as not finite
        assert all(is_number_text(w) for w in words)
        assert not np.all(np.isfinite(found[0]))


def _peak_bytes(data: bytes, name: str) -> int:
    tracemalloc.start()
    try:
        parse_map(data, name)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def _columns_map(blocks: int, kind: str) -> bytes:
    """``blocks`` random 1 x 1 m columns with a colour in a 1,000 m square, as text or JSON."""
    rng = np.random.default_rng(1)
    corners = np.round(rng.uniform(0, 990, (blocks, 2)), 3)
    tops = np.round(rng.uniform(1, 40, blocks), 3)
    if kind == "txt":
        lines = ["boundary 0 0 0 1000 1000 50"] + [
            f"block {x} {y} 0 {x + 1:.3f} {y + 1:.3f} {top} 128 128 128"
            for (x, y), top in zip(corners.tolist(), tops.tolist(), strict=True)]
        return ("\n".join(lines) + "\n").encode()
    return json.dumps({"bounds": {"extents": [0, 1000, 0, 1000, 0, 50]}, "blocks": [
        {"extents": [x, round(x + 1, 3), y, round(y + 1, 3), 0, top], "color": [0.5] * 3}
        for (x, y), top in zip(corners.tolist(), tops.tolist(), strict=True)]}, indent=1
        ).encode()


@pytest.mark.parametrize("kind", ["txt", "json"])
def test_reading_holds_a_few_hundred_bytes_a_block(kind):
    """Each further block costs its file text, its numbers in arrays and the World's copy
    of them: under 600 bytes (Python's allocations, as tracemalloc counts them; lists of
    lists and a dict a block took 850 for text and 1,400 for JSON)."""
    small, large = 30_000, 90_000
    grows = (_peak_bytes(_columns_map(large, kind), f"m.{kind}")
             - _peak_bytes(_columns_map(small, kind), f"m.{kind}"))
    assert grows / (large - small) < 600
