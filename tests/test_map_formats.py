"""Reading and writing the text and JSON map formats, quirks and errors included."""

from __future__ import annotations

import os
import stat
import warnings

import numpy as np
import pytest

from quadnav.errors import MapError, MapWarning, QuadnavError
from quadnav.world import parse_map, read_map, write_map
from quadnav.world.startgoal import parse_start_goal


def text(content: str):
    return parse_map(content.encode(), "m.txt")


def json_(content: str):
    return parse_map(content.encode(), "m.json")


def map_error(parse, content: str) -> str:
    with pytest.raises(MapError) as info:
        parse(content)
    return str(info.value)


# ----------------------------------------------------------------------------- text format
def test_text_quirks_all_at_once():
    world = text(
        "# a comment\r\n"
        "\r\n"
        "block\t1.000000\t1 0   2 2 1 255 0 0  # trailing comment\r\n"
        "   \t\r\n"
        "block 1.5 1.5 0.5 3 3 2\r\n"            # 6 fields, overlaps the first
        "boundary 0 0 0 10 10 5 255 255 255\r\n"  # after the blocks, with a colour
    )
    np.testing.assert_array_equal(world.boundary, [0, 0, 0, 10, 10, 5])
    np.testing.assert_array_equal(world.blocks, [[1, 1, 0, 2, 2, 1], [1.5, 1.5, 0.5, 3, 3, 2]])
    np.testing.assert_array_equal(world.colors[0], [1, 0, 0])
    assert world.start is None and world.goal is None and world.margin is None
    # Overlap counted once: 1 + 1.5 * 1.5 * 1.5 - 0.5 * 0.5 * 0.5 of 500 m^3.
    assert world.free_volume_fraction() == pytest.approx(1 - (1 + 3.375 - 0.125) / 500)


@pytest.mark.parametrize(("content", "expected"), [
    ("", "m.txt: empty map"),
    ("# only a comment\n\n", "m.txt: empty map"),
    ("boundary 0 0 0 1 1 1\nbox 0 0 0 1 1 1\n", "m.txt:2: unknown keyword 'box'"),
    ("boundary 0 0 0 1 1\n", "m.txt:1: boundary: expected 6 numbers"),
    ("boundary 0 0 0 1 1 1\nblock 0 0 0 1 1 1 1 1\n", "m.txt:2: block: expected 6 numbers"),
    ("boundary 0 0 0 1 1 1\n\nblock 0 0 zero 1 1 1\n", "m.txt:3: block: expected a number, got 'zero'"),
    ("boundary 0 0 0 1 1 nan\n", "m.txt:1: boundary: expected a finite number"),
    ("boundary 0 0 0 1 1 inf\n", "m.txt:1: boundary: expected a finite number"),
    ("boundary 0 0 0 1 1 0\n", "m.txt:1: boundary: zero thickness along z (zmin = zmax = 0): "
                               "expected a box with a volume"),
    ("boundary 0 0 0 1e5 1 1\n", "m.txt:1: boundary: expected coordinates from -10,000 to "
                                 "10,000 m, got 100,000"),
    ("boundary 0 0 0 1e-4 1 1\n", "m.txt:1: boundary: the boundary is 0.0001 m along x: "
                                  "expected sides from 0.001 to 20,000 m"),
    ("boundary 0 0 0 1 1 1\nblock " + "1 " * 5000 + "\n", "m.txt:2: line of 10,0"),
    ("block 0 0 0 1 1 1\n", "m.txt: no 'boundary"),
    ("boundary 0 0 0 1 1 1\nboundary 0 0 0 2 2 2\n", "m.txt:2: a second boundary line (the first is line 1)"),
    ("boundary 0 0 0 1 1 1\nblock 0 0 0 1 1 1 300 0 0\n", "m.txt:2: block: expected colour values in 0..255"),
])
def test_text_errors_name_file_line_and_expectation(content, expected):
    assert map_error(text, content).startswith(expected)


def test_text_block_partly_outside_is_clipped_and_wholly_outside_dropped():
    with pytest.warns(MapWarning) as record:
        world = text("boundary 0 0 0 10 10 5\n"
                     "block -1 2 0 3 4 6\n"       # clipped on x and z
                     "block 20 20 0 21 21 1\n"    # dropped
                     "block 10 0 0 11 1 1\n"      # only touches: dropped
                     "block 1 1 1 2 2 2\n")
    messages = [str(w.message) for w in record]
    assert messages == ["m.txt:2: block extends past the boundary; clipped to it",
                        "m.txt:3: block lies outside the boundary; dropped",
                        "m.txt:4: block lies outside the boundary; dropped"]
    np.testing.assert_array_equal(world.blocks, [[0, 2, 0, 3, 4, 5], [1, 1, 1, 2, 2, 2]])


def test_blocks_inside_the_boundary_give_no_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        text("boundary 0 0 0 10 10 5\nblock 0 0 0 10 10 5\n")


def warnings_and_world(parse, content: str):
    """The MapWarning messages and the World of parsing ``content``."""
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        world = parse(content)
    assert all(issubclass(w.category, MapWarning) for w in record)
    return [str(w.message) for w in record], world


def test_text_swapped_extents_are_read_as_the_box_between_with_a_warning():
    messages, world = warnings_and_world(text, (
        "boundary 10 0 0 0 10 5\n"               # x swapped
        "block 1 1 3 2 2 0  # z swapped\n"
        "block 4 9 0 3 8 5\n"                    # x and y swapped
        "block 5 5 1 6 6 1\n"                    # zero thickness: dropped
        "block 7 7 0 8 8 1\n"))
    np.testing.assert_array_equal(world.boundary, [0, 0, 0, 10, 10, 5])
    np.testing.assert_array_equal(world.blocks, [[1, 1, 0, 2, 2, 3], [3, 8, 0, 4, 9, 5],
                                                 [7, 7, 0, 8, 8, 1]])
    assert messages == [
        "m.txt:1: boundary: min and max swapped (xmin 10 > xmax 0); read as the box "
        "between them",
        "m.txt:2: block: min and max swapped (zmin 3 > zmax 0); read as the box between them",
        "m.txt:3: block: min and max swapped (xmin 4 > xmax 3, ymin 9 > ymax 8); read as "
        "the box between them",
        "m.txt:4: block: zero thickness along z (zmin = zmax = 1); dropped"]


def test_json_swapped_extents_as_in_the_meam620_lab_maze_files():
    # A thin wall written max first, as the current lab maze files have it.
    messages, world = warnings_and_world(json_, (
        '{"bounds": {"extents": [-2, 2, 3, -3, 0, 2]},\n'
        ' "blocks": [\n'
        '  {"extents": [-1.04, -1.06, -3, 1, 0, 2], "color": [1, 0, 0]},\n'
        '  {"extents": [0.5, 0.5, -3, 3, 0, 2]},\n'
        '  {"extents": [1, 1.5, 2, 2.5, 0, 1]}],\n'
        ' "start": [-1.5, -2, 1], "goal": [1.5, 2, 1]}'))
    np.testing.assert_array_equal(world.boundary, [-2, -3, 0, 2, 3, 2])
    np.testing.assert_array_equal(world.blocks, [[-1.06, -3, 0, -1.04, 1, 2],
                                                 [1, 2, 0, 1.5, 2.5, 1]])
    np.testing.assert_array_equal(world.colors, [[1, 0, 0], [0.6, 0.6, 0.6]])
    assert messages == [
        "m.json:1: bounds: min and max swapped (ymin 3 > ymax -3); read as the box between "
        "them",
        "m.json:3: blocks[0]: min and max swapped (xmin -1.04 > xmax -1.06); read as the box "
        "between them",
        "m.json:4: blocks[1]: zero thickness along x (xmin = xmax = 0.5); dropped"]
    # The wall is where the file meant it: a path through it collides, one round it does not.
    assert not world.segment_free([-1.5, -2, 1], [-0.5, -2, 1])
    assert world.segment_free([-1.5, 2, 1], [-0.5, 2, 1])


# ----------------------------------------------------------------------------- JSON format
def test_json_fields_and_interleaved_extents():
    world = json_('{"bounds": {"extents": [0, 10, -5, 20, 0, 6]},\n'
                  ' "blocks": [{"extents": [1, 2, 3, 4, 0, 5], "color": [0, 0.5, 1]},\n'
                  '            {"extents": [5, 6, 7, 8, 1, 2]}],\n'
                  ' "start": [0.1, -4.9, 0.2], "goal": [8, 18, 3], "margin": 0.3,\n'
                  ' "resolution": [0.2, 0.2, 1], "expected_path_length": Infinity}')
    np.testing.assert_array_equal(world.boundary, [0, -5, 0, 10, 20, 6])
    np.testing.assert_array_equal(world.blocks, [[1, 3, 0, 2, 4, 5], [5, 7, 1, 6, 8, 2]])
    np.testing.assert_array_equal(world.colors[0], [0, 0.5, 1])
    np.testing.assert_array_equal(world.start, [0.1, -4.9, 0.2])
    assert world.margin == 0.3


@pytest.mark.parametrize(("content", "expected"), [
    ("", "m.json: empty map"),
    ("  \n", "m.json: empty map"),
    ('{"bounds": {"extents": [0, 1, 0, 1, 0, 1]},\n "blocks": [\n', "m.json:3: broken JSON"),
    ('{"bounds": {"extents": [0, 1, 0, 1, 0, 1]}}\n}', "m.json:2: broken JSON"),
    ("[1, 2, 3]", "m.json:1: expected a JSON object at the top level"),
    ('{\n"blocks": []}', 'm.json:1: missing key "bounds"'),
    ('{"bounds": {}}', 'm.json:1: bounds: expected an object with "extents"'),
    ('{"bounds": {"extents": [0, 1, 0, 1, 0]}}', "m.json:1: bounds.extents: expected a list of 6"),
    ('{"bounds": {"extents": [0, 1, 0, 1, 0, "1"]}}', "m.json:1: bounds.extents: expected a list of 6"),
    ('{"bounds": {"extents": [0, 1, 0, 1, 0, true]}}', "m.json:1: bounds.extents: expected a list of 6"),
    ('{"bounds": {"extents": [0, 1, 0, 1, 0, NaN]}}', "m.json:1: bounds.extents: expected a finite"),
    ('{"bounds": {"extents": [0, 1, 0, 1, 0, 1e999]}}', "m.json:1: bounds.extents: expected a finite"),
    ('{"bounds": {"extents": [1, 1, 0, 1, 0, 1]}}', "m.json:1: bounds: zero thickness along x"),
    ('{"bounds": {"extents": [-1e154, 1e154, 0, 1, 0, 1]}}', "m.json:1: bounds: expected "
                                                            "coordinates from -10,000"),
    ('{"bounds": {"extents": [0, 9, 0, 9, 0, 9]},\n"blocks": {}}', 'm.json:1: "blocks": expected a list'),
    ('{"bounds": {"extents": [0, 9, 0, 9, 0, 9]},\n"blocks": [\n{"extents": [0, 1, 0, 1, 0, 1]},\n'
     '{"extent": [0, 1, 0, 1, 0, 1]}]}', 'm.json:4: blocks[1]: expected an object with "extents"'),
    ('{"bounds": {"extents": [0, 9, 0, 9, 0, 9]},\n"blocks": [\n'
     '{"extents": [0, 1, 0, 1, 0, 1], "color": [255, 0, 0]}]}', "m.json:3: blocks[0].color: expected colour values in 0..1"),
    ('{"bounds": {"extents": [0, 9, 0, 9, 0, 9]}, "start": [1, 2]}', "m.json:1: start: expected a list of 3"),
    ('{"bounds": {"extents": [0, 9, 0, 9, 0, 9]}, "margin": -1}', "m.json:1: margin: expected from 0 to 100 m, got -1"),
    ('{"bounds": {"extents": [0, 9, 0, 9, 0, 9]},\n"goal": [1, 2, 3e4]}', "m.json:1: goal: expected coordinates from -10,000 to 10,000 m, got 30,000"),
    ('{"bounds": {"extents": [0, 9, 0, 9, 0, 9]}, "margin": "big"}', "m.json:1: margin: expected a number, got \"big\""),
    ('{"bounds": {"extents": [0, 9, 0, 9, 0, 1' + "0" * 400 + ']}}', "m.json:1: bounds.extents: expected a finite number"),
    ('{"bounds": {"extents": [0, 9, 0, 9, 0, 1' + "0" * 5000 + ']}}', "m.json:1: bounds.extents: expected a finite number"),
])
def test_json_errors_name_file_line_and_expectation(content, expected):
    assert map_error(json_, content).startswith(expected)


def test_json_without_blocks_is_an_empty_world():
    world = json_('{"bounds": {"extents": [0, 4.5, 0, 6.5, 0, 3]}}')
    assert world.blocks.shape == (0, 6) and world.colors.shape == (0, 3)


def test_format_is_sniffed_when_the_extension_says_nothing():
    assert len(parse_map(b'{"bounds": {"extents": [0, 1, 0, 1, 0, 1]}}', "map")) == 0
    assert len(parse_map(b"boundary 0 0 0 1 1 1\nblock 0 0 0 1 1 1", "map")) == 1


def test_binary_and_non_utf8_files_are_map_errors():
    with pytest.raises(MapError, match=r"b\.txt: not a UTF-8 text file"):
        parse_map(b"\xff\xfe", "b.txt")
    with pytest.raises(MapError, match="NUL"):
        parse_map(b"boundary\x00", "b.txt")


def test_missing_file_is_a_map_error(tmp_path):
    with pytest.raises(MapError, match=r"nope\.txt: cannot read"):
        read_map(tmp_path / "nope.txt")


# ------------------------------------------------------------------------- writing
def test_write_both_formats_and_read_back(tmp_path):
    world = json_('{"bounds": {"extents": [0, 10, -5, 20, 0, 6]},'
                  ' "blocks": [{"extents": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6], "color": [0.25, 0.5, 1]}],'
                  ' "start": [0.1, -4.9, 0.2], "goal": [8, 18, 3], "margin": 0.3}')
    write_map(world, tmp_path / "w.json")
    again = read_map(tmp_path / "w.json")
    for field in ("boundary", "blocks", "colors", "start", "goal"):
        np.testing.assert_array_equal(getattr(again, field), getattr(world, field))
    assert again.margin == 0.3
    write_map(world, tmp_path / "w.txt")
    as_text = read_map(tmp_path / "w.txt")
    np.testing.assert_array_equal(as_text.blocks, world.blocks)
    np.testing.assert_array_equal(as_text.colors, world.colors)
    assert "# start: (0.1, -4.9, 0.2)" in (tmp_path / "w.txt").read_text()


def test_a_failed_write_leaves_nothing_behind(tmp_path):
    world = text("boundary 0 0 0 1 1 1\n")
    with pytest.raises(QuadnavError, match="cannot write"):
        write_map(world, tmp_path / "missing-folder" / "w.json")
    (tmp_path / "folder.json").mkdir()
    with pytest.raises(QuadnavError, match="cannot write"):
        write_map(world, tmp_path / "folder.json")
    assert [p.name for p in tmp_path.iterdir()] == ["folder.json"]
    assert list((tmp_path / "folder.json").iterdir()) == []


def test_written_maps_get_ordinary_permissions(tmp_path):
    mask = os.umask(0o022)
    try:
        write_map(text("boundary 0 0 0 1 1 1\n"), tmp_path / "w.txt")
    finally:
        os.umask(mask)
    assert stat.S_IMODE((tmp_path / "w.txt").stat().st_mode) == 0o644


# ----------------------------------------------------------------------- start/goal files
def test_start_goal_file_variants():
    start, goal = parse_start_goal("# map1 real\n\nstart:  (0,0,0)\ngoal: (-0.59, 6.81, 0)", "sg.txt")
    np.testing.assert_array_equal(start, [0, 0, 0])
    np.testing.assert_array_equal(goal, [-0.59, 6.81, 0])
    start, goal = parse_start_goal("goal: 1 2 3\r\nStart: (4 5 6)\r\n", "sg.txt")
    np.testing.assert_array_equal(start, [4, 5, 6])


@pytest.mark.parametrize(("content", "expected"), [
    ("start: (0, 0, 0)\n", "sg.txt: no 'goal: (x, y, z)' line"),
    ("start: (0, 0)\ngoal: (1, 1, 1)", "sg.txt:1: start: expected 3 numbers"),
    ("start: (0, 0, x)\ngoal: (1, 1, 1)", "sg.txt:1: start: expected a number, got 'x'"),
    ("begin: (0, 0, 0)", "sg.txt:1: expected 'start: (x, y, z)'"),
    ("start: (0, 0, 0)\nstart: (0, 0, 0)", "sg.txt:2: a second 'start' line"),
    ("start: (0, 0, 0)\ngoal: (1, -2e4, 1)", "sg.txt:2: goal: expected coordinates from -10,000"),
])
def test_start_goal_errors(content, expected):
    with pytest.raises(MapError) as info:
        parse_start_goal(content, "sg.txt")
    assert str(info.value).startswith(expected)
