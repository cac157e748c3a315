"""``quadnav traj``: from a planned path to trajectory files, and one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
from clitools import assert_user_error, run_here


def test_plan_then_traj_writes_every_file(tmp_path):
    assert run_here("plan", "forest", "--iterations", "20000", "--time", "60", "--quiet", "-o",
               tmp_path / "plan").returncode == 0
    result = run_here("traj", "forest", "--path", tmp_path / "plan" / "path.csv", "-o",
                 tmp_path / "traj", "--dt", "0.05")
    assert result.returncode == 0, result.stderr
    out = tmp_path / "traj"
    table = np.loadtxt(out / "trajectory.csv", delimiter=",", skiprows=1)
    header = (out / "trajectory.csv").read_text().splitlines()[0]
    assert header == "t,x,y,z,vx,vy,vz,ax,ay,az,yaw"
    mp = np.loadtxt(out / "MP.csv", delimiter=",")
    assert mp.shape == (9, len(table))
    assert np.allclose(mp[:3].T, table[:, 1:4]) and np.allclose(mp[6:].T, table[:, 7:10])
    path = np.loadtxt(tmp_path / "plan" / "path.csv", delimiter=",", skiprows=1)
    assert np.allclose(table[0, 1:4], path[0]) and np.allclose(table[-1, 1:4], path[-1])
    summary = json.loads((out / "trajectory.json").read_text())
    assert summary["method"] == "minsnap" and summary["duration"] == pytest.approx(table[-1, 0])
    assert (summary["timing"], summary["speed"], summary["acceleration"]) == ("fastest", 2, 3)
    assert summary["feasibility"]["min_clearance"]["value"] > 0.2
    for name in ("trajectory.png", "states.png"):
        assert (out / name).read_bytes()[:4] == b"\x89PNG"


def test_traj_bad_input_is_one_line_exit_2(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y,z\n1,1,1\n2,two,2\n")
    out = tmp_path / "out"
    cases = [
        (("forest", "--path", bad), "bad.csv:3: expected three numbers x,y,z from -10,000 to "
                                    "10,000 m, got '2,two,2'"),
        (("forest", "--path", bad, "--dt", "1e-7"), "--dt: expected from 0.0001 to 1 s"),
        (("forest", "--path", tmp_path / "none.csv"), "none.csv: cannot read"),
        (("forest", "--path", bad, "--method", "bezier"), "invalid choice: 'bezier'"),
        (("forest", "--path", bad, "--vmax", "0"), "expected from 0.01 to 100 m/s"),
    ]
    for args, fragment in cases:
        assert_user_error(run_here("traj", *args, "-o", out), fragment)
    good = tmp_path / "good.csv"
    good.write_text("x,y,z\n1,1,1\n19,19,3\n")  # straight through the trees
    assert_user_error(run_here("traj", "forest", "--path", good, "-o", out), "path segment 0 from (1, 1, 1) to (19, 19, 3) touches a block")
    good.write_text("x,y,z\n1,1,1\n1,2,1\n")
    assert_user_error(run_here("traj", "forest", "--path", good, "--method", "cubic", "--corridor",
                          "-o", out), "need method minsnap")
    assert not out.exists()
