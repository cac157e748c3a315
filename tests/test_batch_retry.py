"""A worker process killed mid-batch (a real SIGKILL, by the mission's own planner) loses
none of its missions and duplicates none: the mission it flew flies again on a new worker,
and the table equals the missions flown here; a mission that kills its worker every time
is given up after :data:`~quadnav.batch.executor.RETRIES` more tries, a refused row saying
why, and the batch goes on."""

from __future__ import annotations

import json

import pytest
from batchtools import assert_killer_table, write_killer_spec
from clitools import run_here
from workerjobs import kill_worker, kill_worker_for

from quadnav.batch.executor import RETRIES, LocalExecutor, WorkerDiedError
from quadnav.batch.fly_one import fly_row, load_context
from quadnav.batch.grid import read_spec
from quadnav.batch.table import read_rows, same_row


def test_a_killed_worker_loses_no_mission_and_one_killed_every_time_is_given_up(tmp_path):
    spec = write_killer_spec(tmp_path / "spec")

    result = run_here("batch", spec, "--workers", "2", "--quiet", "-o", tmp_path / "out")

    assert result.returncode == 0, result.stderr
    flew = next(line for line in result.stdout.splitlines() if line.startswith("flew "))
    assert flew.endswith("; 2 flown again after the worker process flying them died"), flew
    assert "1 refused" in result.stdout
    assert_killer_table(spec, tmp_path / "out",
                        f"its worker process died {RETRIES + 1} times (killed by SIGKILL); "
                        "given up")


#: A wind (rotorpy's shape) that kills the worker process flying it (SIGKILL) as it is made.
KILLER_WIND = '''\
import os
import signal


class Killer:
    def __init__(self):
        os.kill(os.getpid(), signal.SIGKILL)

    def update(self, t, position):
        return (0.0, 0.0, 0.0)
'''


def test_a_mission_that_kills_its_worker_every_time_takes_none_sharing_its_plan_with_it(
        tmp_path):
    # four missions of one plan (they differ only in the wind), flown as one job; the
    # third's wind kills its worker every time: the job flies again one mission at a time
    (tmp_path / "room.txt").write_text("boundary 0 0 0 6 6 3\n")
    (tmp_path / "killer.py").write_text(KILLER_WIND)
    spec = tmp_path / "spec.toml"
    spec.write_text('seeds = 1\nspeeds = [2.0]\nmaps = ["room.txt"]\n'
                    'winds = [[0, 0, 0], [0.01, 0, 0], "killer.py:Killer()", [0.02, 0, 0]]\n')

    result = run_here("batch", spec, "--workers", "1", "--quiet", "-o", tmp_path / "out")

    assert result.returncode == 0, result.stderr
    assert "; 4 flown again after the worker process flying them died" in result.stdout
    batch = read_spec(spec)
    missions, context = batch.missions(), load_context(batch)
    rows = read_rows(tmp_path / "out" / "results.csv")
    assert [row["mission_key"] for row in rows] == [mission.key for mission in missions]
    assert len({row["plan_key"] for row in rows if row["success"]}) == 1
    for row, mission in zip(rows, missions, strict=True):
        if row["wind_model"] == f"{tmp_path / 'killer.py'}:Killer()":
            assert (row["success"], row["error"]) == (
                False, f"its worker process died {RETRIES + 1} times (killed by SIGKILL); "
                       "given up")
        else:
            assert row["success"] and same_row(row, fly_row(context, mission))
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert (summary["retried"], summary["errors"]) == (4, 1)


def test_a_job_that_kills_its_worker_every_time_is_an_error_without_a_lost_result():
    with LocalExecutor(shared=10, workers=1) as executor:
        jobs = executor.map_unordered(kill_worker_for, [2, 0])
        assert next(jobs) == (0, 20)
        with pytest.raises(WorkerDiedError, match=f"died {RETRIES + 1} times"):
            next(jobs)
        assert executor.retried == 1


def test_a_worker_that_dies_as_it_starts_is_an_error_at_once():
    with pytest.raises(WorkerDiedError,
                       match=r"^a worker process died as it started \(killed by SIGKILL\)$"), \
            LocalExecutor(shared=10, warm_up=kill_worker, workers=1) as executor:
        list(executor.map_unordered(kill_worker_for, [1, 2]))
