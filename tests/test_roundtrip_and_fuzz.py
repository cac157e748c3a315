"""Round trips between the formats; fuzzing the readers (only MapError ever escapes) and
the command line (every input gets a clean answer)."""

from __future__ import annotations

import contextlib
import re
import signal
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from quadnav.errors import MapError
from quadnav.world import World, load_world, parse_map
from quadnav.world.jsonmap import format_json_map
from quadnav.world.textmap import format_text_map

finite = st.floats(-5e3, 5e3, allow_nan=False, allow_infinity=False)


@st.composite
def worlds(draw) -> World:
    """Worlds with arbitrary float coordinates inside a boundary within the stated range
    (coordinates within 10 km, sides of at least 1 mm and some rounding), as a text map
    gives them."""
    lower = np.array(draw(st.tuples(finite, finite, finite)))
    size = np.array(draw(st.tuples(*[st.floats(2e-3, 5e3)] * 3)))
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


# ------------------------------------------------------------------ the command line
# Every input, however odd, gets a clean answer: exit 0, 1 or 2, and for 2 exactly one
# line "quadnav...: error: ..." on stderr (besides one-line warnings), no traceback, no
# hang. The commands run in this process (quadnav.cli.main.main) to keep this fast.

ERROR_LINE = re.compile(r"^quadnav( [a-z-]+)*: error: \S")
WARNING_LINE = re.compile(r"^quadnav: warning: \S")
#: Seconds one command may take before it counts as hung.
HANG = 60


class HungError(Exception):
    """A command that ran past :data:`HANG` seconds."""


def _hung(signum, frame):
    raise HungError


@pytest.fixture
def quadnav_cli(capsys, monkeypatch):
    """``call(args) -> (exit code, stderr)``, running ``quadnav args`` in this process and
    failing the test on anything but a clean answer."""
    from quadnav.cli import main as cli

    # One parser, with every command, for every call: building it takes most of a call's time.
    parser = cli.build_parser()
    monkeypatch.setattr(cli, "build_parser", lambda argv=None: parser)
    monkeypatch.setattr(warnings, "showwarning", warnings.showwarning)  # main replaces it
    monkeypatch.setattr(signal, "signal", signal.signal)
    previous = signal.signal(signal.SIGALRM, _hung)

    def call(args: list[str]) -> tuple[int, str]:
        capsys.readouterr()
        signal.alarm(HANG)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("always")
                code = cli.main([str(a) for a in args])
        except SystemExit as stop:
            code = stop.code
        except HungError:
            pytest.fail(f"quadnav {' '.join(map(str, args))} ran over {HANG} s")
        finally:
            signal.alarm(0)
        err = capsys.readouterr().err
        where = f"quadnav {' '.join(map(str, args))!r}"[:300]
        assert code in (0, 1, 2), f"{where}: exit {code}\n{err}"
        assert "Traceback" not in err, f"{where}:\n{err}"
        if code == 2:
            lines = err.strip().splitlines()
            errors = [line for line in lines if ERROR_LINE.match(line)]
            assert len(errors) == 1, f"{where}:\n{err}"
            assert all(ERROR_LINE.match(line) or WARNING_LINE.match(line) for line in lines), \
                f"{where}:\n{err}"
        return code, err

    yield call
    signal.signal(signal.SIGALRM, previous)


#: A small map of our own in both formats: a full-height block, with the JSON map's start
#: inside it (so that commands fail fast on the start after checking their flags).
SMALL_TEXT = (b"# small\nboundary 0 0 0 4 4 3\nblock 1 1 0 2 2 3 255 0 0\n"
              b"block 3 3 1 3.5 2.5 2  # swapped y\nblock 0.5 3 0 1 3.5 0.5\n")
SMALL_JSON = (b'{"bounds": {"extents": [0, 4, 0, 4, 0, 3]},\n'
              b' "blocks": [{"extents": [1, 2, 1, 2, 0, 3], "color": [1, 0, 0]},\n'
              b'            {"extents": [3, 3.5, 3, 2.5, 1, 2]}],\n'
              b' "start": [1.5, 1.5, 1], "goal": [3.5, 0.5, 1], "margin": 0.2}\n')

#: Values for numeric flags and parameters: odd, out of range, not numbers at all, or at
#: the edges of the ranges.
ODD = ["0", "-1", "-0", "1e308", "-1e308", "1e999", "nan", "inf", "-inf", "1e-320", "1e-7",
       "1e9", "9" * 30, "9" * 5000, "0x10", "1_000", "abc", "", " ", "1,2", "--", "1e154",
       "-1e154", "4294967296", "2e4", "-2e4", "0.5", "3", "100", "1e4", "0.001", "0.01", "1",
       "10", "60", "3600", "1e5", "1e-4", str(2**63 - 1), str(2**63), "1e7", "-360"]
#: Ordinary values, so that some inputs get past the flags' own checks.
PLAIN = ["0.5", "1", "2", "3", "20"]


def odd_value(rng: np.random.Generator) -> str:
    """A value from :data:`ODD`, or half the time from :data:`PLAIN`."""
    values = ODD if rng.random() < 0.5 else PLAIN
    return values[rng.integers(len(values))]


def test_mutated_map_files_give_clean_answers(tmp_path, quadnav_cli):
    rng = np.random.default_rng(7)
    files = [("m.txt", SMALL_TEXT), ("m.json", SMALL_JSON)]
    for k in range(1000):
        name, data = files[k % 2]
        path = tmp_path / f"{k}{name}"
        path.write_bytes(mutate(data, rng))
        if k % 10 == 0:  # also searches for a path
            quadnav_cli(["map", "check", path, "--margin", "0.1", "--time", "0.5"])
        else:
            quadnav_cli(["map", "info", path])


def odd_spec(rng: np.random.Generator) -> str:
    """A built-in world spec with one to three parameters set to odd values."""
    from quadnav.world.builtin import describe_worlds

    world = describe_worlds()[rng.integers(4)]
    names = [p.name for p in world.params] + ["bogus"]
    items = []
    for _ in range(rng.integers(1, 4)):
        value = odd_value(rng)
        if rng.random() < 0.3:  # a size or grid made of odd parts
            value = "x".join(odd_value(rng) for _ in range(rng.integers(1, 4)))
        items.append(f"{names[rng.integers(len(names))]}={value}")
    return f"{world.name}:{','.join(items)}"


def test_built_in_worlds_with_odd_parameters_give_clean_answers(quadnav_cli):
    rng = np.random.default_rng(11)
    built = 0
    for _ in range(250):
        code, _ = quadnav_cli(["map", "info", odd_spec(rng)])
        built += code == 0
    assert 0 < built < 25  # most specs are refused before anything is built


#: Numeric flags of every command, with their number of values.
FLAGS = {
    ("fly",): {"--speed": 1, "--accel": 1, "--time": 1, "--seed": 1, "--iterations": 1,
               "--physics-rate": 1, "--control-rate": 1, "--wind": 3, "--gusts": 1,
               "--settle": 1, "--margin": 1, "--goal": 3},
    ("plan",): {"--time": 1, "--seed": 1, "--iterations": 1, "--step": 1, "--goal-bias": 1,
                "--goal-tolerance": 1, "--margin": 1, "--goal": 3},
    ("traj",): {"--vmax": 1, "--amax": 1, "--dt": 1, "--margin": 1},
    ("kino", "diffdrive"): {"--height": 1, "--margin": 1, "--seed": 1, "--iterations": 1,
                            "--time": 1, "--goal-radius": 1, "--goal": 2},
    ("kino", "quadrotor"): {"--margin": 1, "--seed": 1, "--iterations": 1, "--time": 1,
                            "--goal-radius": 1, "--goal": 3},
    ("tello", "fly"): {"--yaw": 1, "--speed": 1, "--accel": 1, "--time": 1, "--seed": 1,
                       "--iterations": 1, "--min-battery": 1, "--time-scale": 1,
                       "--margin": 1, "--goal": 3},
    ("map", "check"): {"--margin": 1, "--start": 3, "--goal": 3},
    ("animate",): {"--fps": 1, "--speed": 1, "--max-frames": 1},
    ("blender",): {"--size": 1, "--fps": 1},
}


def base_command(command: tuple[str, ...], folder: Path) -> list[str]:
    """``command`` with the arguments it needs; each fails fast once its flags pass: the
    map's start lies in a block, the path runs through it, the run folder is missing, the
    search for a path is short."""
    small = folder / "small.json"
    if command == ("traj",):
        return ["traj", small, "--path", folder / "through.csv", "-o", folder / "out"]
    if command == ("kino", "diffdrive"):
        return ["kino", "diffdrive", small, "--start", "1.5", "1.5", "0", "--goal", "3", "3",
                "-o", folder / "out"]
    if command in (("animate",), ("blender",)):
        return [*command, folder / "no-run", "-o", folder / "out.gif"]
    if command == ("map", "check"):  # searches for a path once start and goal are usable
        return ["map", "check", small, "--time", "0.2"]
    return [*command, small, "-o", folder / "out"]


def test_odd_command_lines_give_clean_answers(tmp_path, quadnav_cli):
    (tmp_path / "small.json").write_bytes(SMALL_JSON)
    (tmp_path / "through.csv").write_text("x,y,z\n0.5,1.5,1\n3.5,1.5,1\n")
    rng = np.random.default_rng(5)
    commands = list(FLAGS)
    for _ in range(1000):
        command = commands[rng.integers(len(commands))]
        args = base_command(command, tmp_path)
        flags = list(FLAGS[command])
        for _ in range(rng.integers(1, 4)):
            flag = flags[rng.integers(len(flags))]
            args += [flag, *(odd_value(rng) for _ in range(FLAGS[command][flag]))]
        quadnav_cli(args)
    # The emulator runs until Ctrl-C once its flags pass: only out-of-range values here.
    for flag, value in (("--yaw", "1e9"), ("--time-scale", "0"), ("--start", "nan")):
        code, err = quadnav_cli(["tello", "emulate", flag, *[value] * (3 if flag == "--start" else 1)])
        assert code == 2 and flag in err


#: Values that pass the flags of plan, at the edges of their ranges.
EDGES = {"--step": ["0.001", "1e4", "0.05"], "--goal-tolerance": ["0.001", "1e4"],
         "--goal-bias": ["0", "0.999"], "--seed": ["0", str(2**63 - 1)],
         "--margin": ["0", "0.3"]}


def test_a_few_real_plans_at_the_edges_of_the_ranges_give_clean_answers(tmp_path, quadnav_cli):
    (tmp_path / "small.txt").write_bytes(SMALL_TEXT)
    rng = np.random.default_rng(3)
    codes = []
    for k in range(4):
        args = ["plan", tmp_path / "small.txt", "--start", "0.5", "0.5", "1", "--goal", "3.5",
                "3.5", "1", "--iterations", "500", "--quiet", "-o", tmp_path / f"out{k}"]
        for flag, values in EDGES.items():
            args += [flag, values[rng.integers(len(values))]]
        codes.append(quadnav_cli(args)[0])
    assert set(codes) <= {0, 1}  # every value was accepted and the search ran
