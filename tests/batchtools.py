"""A small batch for the batch tests: 2 maps (a built-in world with its own start and goal,
and a map file without, whose start and goal each seed draws) x 3 seeds at 2 m/s, with a
short search budget; and its rows flown one by one in this process. And a batch whose
planner kills its worker process, once for one mission and every time for another; and
one whose planner stalls on one node of a Ray cluster."""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numba
import pyarrow.parquet as pq

from quadnav.batch.fly_one import fly_row, load_context
from quadnav.batch.grid import read_spec
from quadnav.batch.table import read_rows, same_row

SPEC = """\
seeds = 3
speeds = [2.0]
improve = 2000
maps = ["window:size=4x6x3,walls=1", "pillar.txt"]
"""
PILLAR_MAP = "boundary 0 0 0 6 6 3\nblock 2.5 2.5 0 3.5 3.5 3\n"
MISSIONS = 6


def write_spec(folder: Path, text: str = SPEC) -> Path:
    """The test spec (and its map file) in ``folder``; returns the spec's path."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "pillar.txt").write_text(PILLAR_MAP)
    path = folder / "spec.toml"
    path.write_text(text)
    return path


@functools.cache
def _rows_one_by_one(spec_path: str) -> tuple[dict, ...]:
    spec = read_spec(spec_path)
    context = load_context(spec)
    return tuple(fly_row(context, mission) for mission in spec.missions())


def rows_one_by_one(spec_path: Path) -> list[dict]:
    """The rows of the spec's missions flown in this process, one after the other."""
    return list(_rows_one_by_one(str(spec_path)))



def numba_threads_in_worker(shared: object, item: object) -> int:
    """A job for an executor: the numba threads its worker's kernels run on."""
    return numba.get_num_threads()


#: A plain planner (a straight path: the killer spec's map has no blocks) that kills its
#: own process with SIGKILL when it plans for seed ``once`` the first time (in the process
#: that makes the file ``marker``), and for seed ``always`` every time.
KILLER = '''\
import os
import signal

import numpy as np


def plan(world, start, goal, margin, seed=0, once=-1, always=-1, marker=""):
    if seed == always:
        os.kill(os.getpid(), signal.SIGKILL)
    if seed == once:
        try:
            os.close(os.open(marker, os.O_CREAT | os.O_EXCL))
        except FileExistsError:
            pass
        else:
            os.kill(os.getpid(), signal.SIGKILL)
    return np.array([start, goal])
'''
#: Missions of the killer spec, and the seeds whose worker dies once and every time.
KILLER_MISSIONS, KILLED_ONCE, KILLED_ALWAYS = 6, 1, 3


def write_killer_spec(folder: Path) -> Path:
    """A spec of :data:`KILLER_MISSIONS` missions in a room without blocks (a start and
    goal drawn per seed) planned by :data:`KILLER`, whose marker is ``folder``/killed;
    returns the spec's path."""
    return _write_room_spec(folder, "killer", KILLER,
                            f"once={KILLED_ONCE}, always={KILLED_ALWAYS}, "
                            f"marker='{folder / 'killed'}'")


#: A plain planner (a straight path, as :data:`KILLER`'s) that, in a process of the test
#: cluster's node ``node`` (named by its QUADNAV_TEST_NODE, tests/raycluster.py), writes
#: the node's name and its process id in the file ``marker`` and then sleeps until killed.
STALLER = '''\
import os
import time

import numpy as np


def plan(world, start, goal, margin, seed=0, node="", marker=""):
    if os.environ.get("QUADNAV_TEST_NODE") == node:
        with open(marker + ".part", "w") as part:
            part.write(f"{node} {os.getpid()}")
        os.replace(marker + ".part", marker)
        while True:
            time.sleep(60)
    return np.array([start, goal])
'''


def write_staller_spec(folder: Path, node: str) -> Path:
    """The missions of :func:`write_killer_spec` planned by :data:`STALLER`, stalling on
    ``node``, whose marker is ``folder``/stalled; returns the spec's path."""
    return _write_room_spec(folder, "staller", STALLER,
                            f"node='{node}', marker='{folder / 'stalled'}'")


def _write_room_spec(folder: Path, planner: str, source: str, arguments: str) -> Path:
    """A spec of :data:`KILLER_MISSIONS` missions in a room without blocks (a start and
    goal drawn per seed) planned by the function ``plan`` of ``source``, written in
    ``folder`` as the file ``planner``.py, called with ``arguments``; returns its path."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "room.txt").write_text("boundary 0 0 0 6 6 3\n")
    (folder / f"{planner}.py").write_text(source)
    path = folder / "spec.toml"
    path.write_text(f"seeds = {KILLER_MISSIONS}\nspeeds = [2.0]\nmaps = [\"room.txt\"]\n"
                    f"planners = [\"{planner}.py:plan({arguments})\"]\n")
    return path


def assert_killer_table(spec_path: Path, out: Path, reason: str) -> None:
    """The killer spec's batch in ``out`` has every mission once, in the grid's order: the
    one killed once equal to the others flown here, the one killed every time a refused
    row saying ``reason``; its summary counts both as retried."""
    assert (spec_path.parent / "killed").exists()  # flying here kills no more
    spec = read_spec(spec_path)
    context = load_context(spec)
    rows = read_rows(out / "results.csv")
    assert [row["mission_key"] for row in rows] == [m.key for m in spec.missions()]
    for row, mission in zip(rows, spec.missions(), strict=True):
        if mission.seed == KILLED_ALWAYS:
            assert (row["success"], row["path_found"], row["error"]) == (False, False, reason)
            assert row["start_goal_drawn"] and row["start_x"] is None
        else:
            assert row["error"] is None and row["success"]
            assert same_row(row, fly_row(context, mission))
    assert pq.read_table(out / "results.parquet").to_pylist() == rows
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["retried"], summary["errors"], summary["complete"]) == (2, 1, True)
