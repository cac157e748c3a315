"""A worker process killed mid-batch (a real SIGKILL, by the mission's own planner) loses
none of its missions and duplicates none: the mission it flew flies again on a new worker,
and the table equals the missions flown here; a mission that kills its worker every time
is given up after :data:`~quadnav.batch.executor.RETRIES` more tries, a refused row saying
why, and the batch goes on."""

from __future__ import annotations

import os
import signal

import pytest
from batchtools import assert_killer_table, write_killer_spec
from clitools import run_here

from quadnav.batch.executor import RETRIES, LocalExecutor, WorkerDiedError


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


def kill_worker_for(shared: object, item: int) -> int:
    """A job: ``item`` times ``shared``, or for item 0 its worker killed (SIGKILL)."""
    if item == 0:
        os.kill(os.getpid(), signal.SIGKILL)
    return shared * item


def test_a_job_that_kills_its_worker_every_time_is_an_error_without_a_lost_result():
    with LocalExecutor(shared=10, workers=1) as executor:
        jobs = executor.map_unordered(kill_worker_for, [2, 0])
        assert next(jobs) == (0, 20)
        with pytest.raises(WorkerDiedError, match=f"died {RETRIES + 1} times"):
            next(jobs)
        assert executor.retried == 1


def kill_worker(shared: object) -> None:
    """A warm-up that kills its worker (SIGKILL)."""
    os.kill(os.getpid(), signal.SIGKILL)


def test_a_worker_that_dies_as_it_starts_is_an_error_at_once():
    with pytest.raises(WorkerDiedError,
                       match=r"^a worker process died as it started \(killed by SIGKILL\)$"), \
            LocalExecutor(shared=10, warm_up=kill_worker, workers=1) as executor:
        list(executor.map_unordered(kill_worker_for, [1, 2]))
