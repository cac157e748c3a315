"""Round trips between the formats, and fuzzing the readers: only MapError ever escapes."""

from __future__ import annotations

import contextlib
import warnings
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from quadnav.errors import MapError
from quadnav.world import World, load_world, parse_map
from quadnav.world.jsonmap import format_json_map
from quadnav.world.textmap import format_text_map

finite = st.floats(-1e6, 1e6, allow_nan=False, allow_infinity=False)


@st.composite
def worlds(draw) -> World:
    """Worlds with arbitrary float coordinates inside a boundary, as a text map gives them."""
    lower = np.array(draw(st.tuples(finite, finite, finite)))
    size = np.array(draw(st.tuples(*[st.floats(1e-3, 1e6)] * 3)))
    n = draw(st.integers(0, 5))
    fractions = draw(arrays(np.float64, (n, 2, 3), elements=st.floats(0, 1)))
    fractions.sort(axis=1)
    blocks = (lower + fractions * size).reshape(-1, 6)
    # Colours as the text reader makes them: any number in 0..255, divided by 255.
    colors = draw(arrays(np.float64, (n, 3), elements=st.floats(0, 255))) / 255
    valid = np.all(blocks[:, :3] < blocks[:, 3:], axis=1)
    return World(boundary=np.concatenate([lower, lower + size]), blocks=blocks[valid],
                 colors=colors[valid])


def same_numbers(a: World, b: World) -> None:
    np.testing.assert_array_equal(a.boundary, b.boundary)
    np.testing.assert_array_equal(a.blocks, b.blocks)
    np.testing.assert_array_equal(a.colors, b.colors)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(worlds())
def test_text_to_json_to_text_keeps_every_number(world):
    text = format_text_map(world)
    from_text = parse_map(text.encode(), "w.txt")
    same_numbers(from_text, world)
    via_json = parse_map(format_json_map(from_text).encode(), "w.json")
    same_numbers(via_json, world)
    assert format_text_map(via_json.replace(name=world.name)) == text


@settings(max_examples=100, deadline=None)
@given(worlds(), st.tuples(finite, finite, finite), st.floats(0, 10))
def test_json_round_trip_keeps_start_goal_and_margin(world, point, margin):
    world = world.replace(start=point, goal=point[::-1], margin=margin)
    again = parse_map(format_json_map(world).encode(), "w.json")
    same_numbers(again, world)
    np.testing.assert_array_equal(again.start, world.start)
    np.testing.assert_array_equal(again.goal, world.goal)
    assert again.margin == world.margin


def read_only_map_errors(data: bytes, name: str) -> None:
    """Parse ``data``; anything but a World or a MapError fails the test."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with contextlib.suppress(MapError):
            parse_map(data, name)


@settings(max_examples=500, deadline=None)
@given(st.binary(max_size=300), st.sampled_from(["f.txt", "f.json", "f"]))
def test_random_bytes_raise_only_map_errors(data, name):
    read_only_map_errors(data, name)


@settings(max_examples=300, deadline=None)
@given(st.text(alphabet="boundaryblck0123456789.-+eE \t\n#{}[]\":,nafitxtsgol", max_size=200),
       st.sampled_from(["f.txt", "f.json"]))
def test_map_like_text_raises_only_map_errors(content, name):
    read_only_map_errors(content.encode(), name)


MUTATION_TOKENS = [b"nan", b"inf", b"-", b"1e999", b"{", b"}", b"[", b"]", b",", b'"', b"\t",
                   b"\n", b"#", b"block", b"boundary", b"\xff", b"0", b"null", b"true", b"1e-320"]


def mutate(data: bytes, rng: np.random.Generator) -> bytes:
    """``data`` with a few random deletions, insertions, replacements or line duplications."""
    out = bytearray(data)
    for _ in range(rng.integers(1, 4)):
        pos = int(rng.integers(0, len(out) + 1))
        kind = rng.integers(0, 4)
        if kind == 0 and out:
            del out[pos:pos + int(rng.integers(1, 8))]
        elif kind == 1:
            out[pos:pos] = MUTATION_TOKENS[rng.integers(len(MUTATION_TOKENS))]
        elif kind == 2:
            out[pos:pos + 1] = bytes([int(rng.integers(0, 256))])
        else:
            lines = bytes(out).splitlines(keepends=True)
            if lines:
                i = int(rng.integers(len(lines)))
                lines.insert(i, lines[i])
            out = bytearray(b"".join(lines))
    return bytes(out)


def corpus(shared_folder: Path | None) -> list[tuple[str, bytes]]:
    """(name, bytes) of the real maps (when the folder is there) and of built-in worlds."""
    files: list[tuple[str, bytes]] = []
    if shared_folder is not None:
        files += [(p.name, p.read_bytes()) for p in shared_folder.rglob("*")
                  if p.suffix in (".txt", ".json")]
    for spec in ("forest", "window", "maze"):
        world = load_world(spec)
        files += [("b.txt", format_text_map(world).encode()), ("b.json", format_json_map(world).encode())]
    return files


def test_mutated_real_maps_raise_only_map_errors(optional_shared_maps):
    rng = np.random.default_rng(2026)
    files = corpus(optional_shared_maps)
    for _ in range(3000):
        name, data = files[rng.integers(len(files))]
        read_only_map_errors(mutate(data, rng), name)
