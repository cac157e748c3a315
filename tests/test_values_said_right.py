"""Refusals that say what they refuse: a value shown with the digits that put it out of
range, a long token cut, an empty output path, a vehicle file that is missing or is no
file at all."""

from __future__ import annotations

import json
import os

import pytest
from clitools import assert_user_error, run_here

from quadnav.errors import MapError, QuadnavError
from quadnav.limits import COORDINATE
from quadnav.vehicle.params import load_params
from quadnav.world import parse_map


@pytest.mark.parametrize(("value", "shown"), [(10000.001, "10000.001"),
                                              (-10000.0000001, "-10000.0000001"),
                                              (1e300, "1e+300"), (20_000, "20,000")])
def test_a_refused_value_is_shown_with_the_digits_that_refuse_it(value, shown):
    with pytest.raises(QuadnavError) as info:
        COORDINATE.check(value, "x")
    assert str(info.value) == f"x: expected from -10,000 to 10,000 m, got {shown}"
    with pytest.raises(MapError) as info:
        corners = f"{value!r} 0 0 10 10 5" if value < 0 else f"0 0 0 {value!r} 10 5"
        parse_map(f"boundary {corners}\n".encode(), "m.txt")
    assert str(info.value).endswith(f"got {shown}")


def test_a_long_unknown_keyword_is_cut():
    keyword = "x" * 5_000
    with pytest.raises(MapError) as info:
        parse_map(f"boundary 0 0 0 10 10 5\n{keyword} 1 2 3\n".encode(), "m.txt")
    message = str(info.value)
    assert len(message) < 200
    assert message.startswith("m.txt:2: unknown keyword 'xxxxxxxxxxxx...xxxx (5,000 characters)'")


@pytest.mark.parametrize("command", [["fly"], ["plan"], ["traj"], ["batch", "forest"], ["grade", "DIR"],
                                     ["view", "DIR"], ["report", "DIR"], ["tune"]])
@pytest.mark.parametrize("output", ["", "  "])
def test_an_empty_output_path_is_refused_before_anything_is_written(tmp_path, command, output):
    before = sorted(os.listdir(tmp_path))
    result = run_here(*command, "-o", output, cwd=tmp_path)
    assert_user_error(result, "argument -o/--output: expected a file or folder name, got "
                      f"{output!r}")
    assert sorted(os.listdir(tmp_path)) == before


def test_a_missing_vehicle_file_is_called_missing(tmp_path):
    with pytest.raises(QuadnavError) as info:
        load_params(tmp_path / "tello_heavy.toml")
    assert str(info.value).startswith(f"{tmp_path / 'tello_heavy.toml'}: no such file: expected")
    with pytest.raises(QuadnavError, match=r"^boeing: expected a vehicle preset"):
        load_params("boeing")


def test_a_vehicle_file_that_is_no_regular_file_is_refused_without_reading_it(tmp_path):
    fifo = tmp_path / "vehicle.toml"
    os.mkfifo(fifo)
    for path, kind in ((fifo, "a FIFO"), (tmp_path, "a folder")):
        with pytest.raises(QuadnavError) as info:
            load_params(path)
        assert str(info.value) == f"{path}: {kind}, not a regular file: expected a vehicle TOML file"


@pytest.mark.parametrize(("args", "expected"), [
    (["fly", "{fifo}.txt"], "{fifo}.txt: a FIFO, not a regular file: expected a file"),
    (["fly", "forest", "--start-goal", "{fifo}.txt"], "{fifo}.txt: a FIFO, not a regular file"),
    (["fly", "forest", "--gains", "{fifo}.toml"], "{fifo}.toml: a FIFO, not a regular file: "
     "expected a TOML file"),
    (["fly", "--mission", "{fifo}.toml"], "{fifo}.toml: a FIFO, not a regular file"),
    (["fly", "forest", "--controller", "{fifo}.py:Control"], "controller {fifo}.py: a FIFO, "
     "not a Python file"),
    (["traj", "forest", "--path", "{fifo}.txt"], "{fifo}.txt: a FIFO, not a regular file"),
    (["track", "{fifo}.txt"], "{fifo}.txt: a FIFO, not a regular file"),
    (["batch", "{fifo}.toml"], "{fifo}.toml: a FIFO, not a regular file"),
    (["map", "info", "{fifo}.txt"], "{fifo}.txt: a FIFO, not a regular file"),
])
def test_a_fifo_named_as_an_input_is_refused_as_what_it_is(tmp_path, args, expected):
    """Reading a FIFO waits for a writer: before, these hung or called it "no such file"."""
    fifo = tmp_path / "input"
    for suffix in (".txt", ".toml", ".py"):
        os.mkfifo(f"{fifo}{suffix}")
    output = [] if args[0] == "map" else ["-o", tmp_path / "out"]
    result = run_here(*(arg.format(fifo=fifo) for arg in args), *output)
    assert_user_error(result, expected.format(fifo=fifo))
    assert not (tmp_path / "out").exists()


def test_a_flight_and_a_plan_record_what_stopped_their_search(tmp_path):
    """A search ended by --time differs from run to run; the run folder says it was the
    clock (and a sample budget says so too)."""
    by_clock = run_here("fly", "forest", "--time", "0.3", "--improve", "5000000", "--stall",
                        "0", "--no-figures", "--quiet", "-o", tmp_path / "clock")
    by_budget = run_here("plan", "forest", "--improve", "200", "--no-figures", "--quiet",
                         "-o", tmp_path / "budget")
    assert by_clock.returncode == 0 and by_budget.returncode == 0, by_clock.stderr
    metrics = json.loads((tmp_path / "clock" / "metrics.json").read_text())
    assert metrics["search_stopped_by"] == "time"
    plan = json.loads((tmp_path / "budget" / "plan.json").read_text())
    assert plan["stats"]["stopped_by"] == "improvement"
