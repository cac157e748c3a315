"""``quadnav plan``: the files it writes, its exit codes and its one-line errors."""

from __future__ import annotations

import csv
import json
import subprocess
import sys

import numpy as np
from clitools import assert_user_error, run_here

from quadnav.world import load_world


def read_path(folder) -> np.ndarray:
    with open(folder / "path.csv") as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["x", "y", "z"]
    return np.array(rows[1:], dtype=float)


def test_plan_writes_path_stats_and_figure(tmp_path):
    out = tmp_path / "out"
    result = run_here("plan", "forest", "--iterations", "20000", "--time", "60", "--seed", "4", "--quiet", "-o", out)
    assert result.returncode == 0, result.stderr
    world = load_world("forest")
    path = read_path(out)
    assert np.array_equal(path[0], world.start) and np.array_equal(path[-1], world.goal)
    assert world.inflate(0.2).segments_free(np.stack([path[:-1], path[1:]], axis=1)).all()
    summary = json.loads((out / "plan.json").read_text())
    assert summary["solved"] and summary["planner"] == "rrtstar" and summary["seed"] == 4
    assert summary["length"] <= summary["raw_length"]
    assert [step["name"] for step in summary["stats"]["post"]] == ["shortcut", "smooth"]
    assert summary["length"] == summary["stats"]["post"][-1]["length"]
    assert 0 < summary["stats"]["time_to_first"] <= summary["stats"]["seconds"]
    assert (out / "plan.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "search:" in result.stdout and "shortcut:" in result.stdout


def test_same_seed_same_path_file_with_or_without_the_figure(tmp_path):
    args = ("plan", "window", "--iterations", "3000", "--time", "60", "--no-refine", "--quiet")
    assert run_here(*args, "-o", tmp_path / "a").returncode == 0
    result = run_here(*args, "--no-figures", "-o", tmp_path / "b")
    assert result.returncode == 0
    assert (tmp_path / "a" / "path.csv").read_text() == (tmp_path / "b" / "path.csv").read_text()
    assert sorted(p.name for p in (tmp_path / "b").iterdir()) == ["path.csv", "plan.json"]
    assert result.stdout.splitlines()[-1] == f"wrote {tmp_path / 'b' / 'path.csv'}, " \
                                             f"{tmp_path / 'b' / 'plan.json'}"
    assert run_here(*args, "--no-figures", "-o", tmp_path / "a").returncode == 0
    assert not (tmp_path / "a" / "plan.png").exists()  # the earlier run's figure is gone


def test_plan_without_figures_never_loads_matplotlib(tmp_path):
    code = ("import sys; from quadnav.cli.main import main; "
            "main(['plan', '--first', '--no-figures', '--quiet', '-o', 'out']); "
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'matplotlib'))")
    done = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[-1] == "[]"
    assert (tmp_path / "out" / "path.csv").exists()


def test_no_path_in_budget_exits_1_and_keeps_no_stale_path(tmp_path):
    assert run_here("plan", "maze", "--iterations", "20000", "--time", "60", "--quiet", "-o", tmp_path).returncode == 0
    result = run_here("plan", "maze", "--iterations", "3", "--quiet", "-o", tmp_path)
    assert result.returncode == 1
    assert "the search stopped at its cap of 3 samples" in result.stderr
    assert "raise --iterations" in result.stderr
    assert not (tmp_path / "path.csv").exists()
    assert json.loads((tmp_path / "plan.json").read_text())["solved"] is False


def test_start_in_the_margin_warns_and_plans(tmp_path, shared_maps):
    result = run_here("plan", shared_maps / "rbe595" / "map1.txt", "--start", "0", "-5", "0",
                 "--goal", "8", "18", "3", "--iterations", "20000", "--time", "60", "--quiet", "-o", tmp_path)
    assert result.returncode == 0, result.stderr
    assert "warning: start (0, -5, 0) is inside the 0.2 m safety margin; only the straight" in result.stderr
    assert np.array_equal(read_path(tmp_path)[0], [0.0, -5.0, 0.0])


def test_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path, shared_maps):
    out = tmp_path / "out"
    wall = load_world("window").blocks[0]
    in_wall = [str(v) for v in (wall[:3] + wall[3:]) / 2]
    cases = [
        (("forest", "--start", "1", "1", "1", "--goal", "30", "1", "1"), "outside the boundary"),
        (("window", "--start", *in_wall), "inside block 0"),
        ((shared_maps / "meam620" / "test_impossible.json",), "disconnected"),
        (("forest", "--planner", "dijkstra"), "unknown planner 'dijkstra'"),
        (("forest", "--time", "-1"), "expected above 0, at most 3,600 s"),
        (("forest", "--seed", "x"), "expected a whole number from 0"),
        (("forest", "--goal-bias", "1.5"), "expected a number in [0, 1)"),
        (("nosuchmap.txt",), "nosuchmap.txt"),
    ]
    for args, fragment in cases:
        assert_user_error(run_here("plan", *args, "--quiet", "-o", out), fragment)
    assert not out.exists()
    (tmp_path / "file").write_text("")
    assert_user_error(run_here("plan", "forest", "-o", tmp_path / "file"), "expected a folder")
