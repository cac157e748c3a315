"""What a map, start/goal, path or reference file means, character by character: lines end
only at line ends, numbers are ASCII, a JSON key is given once, a number too large for a float
is named by its digits, and a box's swapped extents follow one rule in every format."""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from quadnav.errors import MapError, MapWarning
from quadnav.kinodynamic.world2d import parse_map2d
from quadnav.trajectory.pathfile import read_path_csv
from quadnav.trajectory.references.sampled import read_reference_file
from quadnav.world import parse_map
from quadnav.world.startgoal import parse_start_goal

#: Characters ``str.splitlines`` ends a line at that a text file does not.
NOT_LINE_ENDS = ["\x0b", "\x0c", "\x1c", "\x1d", "\x1e", "\x85", "\u2028", "\u2029"]
BOUNDARY = "boundary 0 0 0 10 10 5\n"


def map_error(parse, *args) -> str:
    with pytest.raises(MapError) as info:
        parse(*args)
    message = str(info.value)
    assert "\n" not in message
    return message


@pytest.mark.parametrize("char", NOT_LINE_ENDS)
def test_a_comment_runs_to_the_line_end_whatever_it_holds(char):
    world = parse_map(f"{BOUNDARY}# note{char}block 1 1 0 9 9 5\n".encode(), "m.txt")
    assert len(world.blocks) == 0
    _, goal = parse_start_goal(f"start: (1, 1, 1)  # was{char}goal: (0, 0, 0)\n"
                                   "goal: (2, 2, 2)\n", "sg.txt")
    np.testing.assert_array_equal(goal, [2, 2, 2])
    plane = parse_map2d(f"boundary 0 0 5 5\n# note{char}rect 1 1 2 2\n", "m.map2d")
    assert len(plane.rects) == 0


def test_windows_and_old_mac_line_ends_still_end_lines():
    world = parse_map(b"boundary 0 0 0 10 10 5\r\nblock 1 1 0 2 2 1\rblock 3 3 0 4 4 1\n",
                      "m.txt")
    assert len(world.blocks) == 2


@given(comment=st.text(alphabet=st.characters(blacklist_characters="\r\n\x00"), max_size=40))
@settings(max_examples=200, deadline=None)
def test_whatever_a_comment_holds_it_adds_nothing(comment):
    plain = parse_map(f"{BOUNDARY}block 1 1 0 2 2 1\n".encode(), "m.txt")
    commented = parse_map(f"{BOUNDARY}# {comment}\nblock 1 1 0 2 2 1  #{comment}\n".encode(),
                          "m.txt")
    np.testing.assert_array_equal(commented.blocks, plain.blocks)


@pytest.mark.parametrize("number", ["1_000", "\u0661\u0662", "\uff13", "\u00b2", "0x10"])
def test_numbers_are_ascii_in_every_text_format(number, tmp_path):
    expected = f"expected a number, got {number!r}"
    assert map_error(parse_map, f"{BOUNDARY}block 1 1 0 {number} 9 5\n".encode(),
                     "m.txt") == f"m.txt:2: block: {expected}"
    assert map_error(parse_start_goal, f"start: (1, {number}, 1)\ngoal: (2, 2, 2)\n",
                     "sg.txt") == f"sg.txt:1: start: {expected}"
    assert map_error(parse_map2d, f"boundary 0 0 5 {number}\n", "m.map2d") \
        == f"m.map2d:1: boundary: {expected}"
    path = tmp_path / "path.csv"
    path.write_text(f"x,y,z\n0,0,1\n1,{number},1\n", encoding="utf-8")
    assert map_error(read_path_csv, path).startswith(f"{path}:3: expected three numbers")
    reference = tmp_path / "MP.csv"
    reference.write_text(f"0,1,2\n0,{number},0\n1,1,1\n", encoding="utf-8")
    assert map_error(read_reference_file, reference) \
        == f"{reference}:2: column 2: expected a number, got {number!r}"


@pytest.mark.parametrize("number", ["1\u0662", "2.\uff15", "1e\u0663"])
def test_json_numbers_are_ascii(number):
    text = '{"bounds": {"extents": [0, 10, 0, 10, 0, 5]},\n "blocks": [{"extents": ' \
        f'[1, {number}, 1, 2, 0, 1]}}]}}'
    assert map_error(parse_map, text.encode(), "m.json") \
        == f"m.json:2: expected a number in ASCII digits, got {number!r}"


def test_a_json_key_given_twice_is_refused_with_its_line():
    text = ('{"bounds": {"extents": [0, 10, 0, 10, 0, 5]},\n'
            ' "blocks": [\n  {"extents": [1, 2, 1, 2, 0, 1], "extents": [5, 6, 5, 6, 0, 1]}]}')
    assert map_error(parse_map, text.encode(), "m.json") \
        == 'm.json:3: key "extents" given twice in one object: expected each key once'
    top = '{"bounds": {"extents": [0, 10, 0, 10, 0, 5]}, "blocks": [],\n"blocks": []}'
    assert map_error(parse_map, top.encode(), "m.json").startswith('m.json:1: key "blocks"')


def test_a_number_beyond_a_float_is_named_by_its_digits_not_called_inf():
    digits = "1" * 5000
    expected = ("expected a finite number, got 111111111111...1111 (5,000 characters), "
                "beyond the largest a 64-bit float holds (1.8e308)")
    json_text = f'{{"bounds": {{"extents": [0, {digits}, 0, 10, 0, 5]}}}}'
    assert map_error(parse_map, json_text.encode(), "m.json") \
        == f"m.json:1: bounds.extents: {expected}"
    assert map_error(parse_map, f"boundary 0 0 0 {digits} 10 5\n".encode(), "m.txt") \
        == f"m.txt:1: boundary: {expected}"
    assert map_error(parse_map, b"boundary 0 0 0 inf 10 5\n", "m.txt") \
        == "m.txt:1: boundary: expected a finite number, got inf"


def test_swapped_extents_follow_one_rule_in_the_2d_format_too():
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        plane = parse_map2d("boundary 5 0 0 5\nrect 2 2 1 1\nrect 3 3 4 3\n", "m.map2d")
    assert all(issubclass(w.category, MapWarning) for w in record)
    assert [str(w.message) for w in record] == [
        "m.map2d:1: boundary: min and max swapped (xmin 5 > xmax 0); read as the box "
        "between them",
        "m.map2d:2: rect: min and max swapped (xmin 2 > xmax 1, ymin 2 > ymax 1); "
        "read as the box between them",
        "m.map2d:3: rect: zero thickness along y (ymin = ymax = 3); dropped"]
    np.testing.assert_array_equal(plane.boundary, [0, 0, 5, 5])
    np.testing.assert_array_equal(plane.rects, [[1, 1, 2, 2]])


def test_a_json_map_padded_with_newlines_reads_in_little_memory(tmp_path):
    """Finding each object's line once kept a list entry per newline: 5.6 GB for a 128 MiB
    file of newlines. Read here under a 1.5 GB address-space limit, the line still right."""
    path = tmp_path / "padded.json"
    padding = 100 * 2**20
    with path.open("w", encoding="utf-8") as file:
        file.write('{"bounds": {"extents": [0, 10, 0, 10, 0, 5]},')
        file.write("\n" * padding)
        file.write('"blocks": [{"extents": [1, 2, 1, 2, 0, 1]},\n'
                   '{"extents": [1, 2, 1, 2, 0, 1], "extents": [1, 2, 1, 2, 0, 1]}]}')
    script = ("import resource, sys\n"
              "resource.setrlimit(resource.RLIMIT_AS, (1536 * 2**20, 1536 * 2**20))\n"
              "from quadnav.errors import MapError\n"
              "from quadnav.world.jsonmap import parse_json_map\n"
              "from quadnav.world.reading import decode_text, read_file\n"
              "try:\n"
              "    parse_json_map(decode_text(read_file(sys.argv[1]), 'p'), 'p')\n"
              "except MapError as error:\n"
              "    print(error)\n")
    done = subprocess.run([sys.executable, "-c", script, str(path)], capture_output=True,
                          text=True, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip() == (f'p:{padding + 2}: key "extents" given twice in one '
                                   "object: expected each key once")


def test_a_map_with_many_repairs_warns_the_first_ten_and_counts_the_rest():
    blocks = "".join(f"block {k + 2} 1 0 {k + 1} 2 1\n" for k in range(50))
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        world = parse_map(f"boundary 0 0 0 100 100 5\n{blocks}".encode(), "m.txt")
    assert len(world.blocks) == 50
    messages = [str(w.message) for w in record]
    assert all(issubclass(w.category, MapWarning) for w in record)
    assert messages[:10] == [f"m.txt:{k + 2}: block: min and max swapped (xmin {k + 2} > "
                             f"xmax {k + 1}); read as the box between them" for k in range(10)]
    assert messages[10:] == ["m.txt: 40 more warnings like these"]
