"""Workers that do not fight each other: each of several local workers runs numba on one
thread, a single local worker keeps numba's own count, the choice is reported, and the
rows are the same with one thread as with numba's own count."""

from __future__ import annotations

import json

import numba
import pytest
from batchtools import MISSIONS, numba_threads_in_worker, rows_one_by_one, write_spec

from quadnav.batch.executor import LocalExecutor
from quadnav.batch.grid import read_spec
from quadnav.batch.run import BatchRun
from quadnav.batch.table import read_rows, same_row


@pytest.fixture
def numbas_own_threads():
    """This process runs numba on numba's own thread count during the test (the suite's
    workers run one thread each: tests/conftest.py)."""
    before = numba.get_num_threads()
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    yield
    numba.set_num_threads(before)


def test_several_local_workers_each_run_one_numba_thread():
    with LocalExecutor(shared=None, workers=2) as executor:
        threads = dict(executor.map_unordered(numba_threads_in_worker, range(4)))

    assert executor.numba_threads == 1
    assert set(threads.values()) == {1}


def test_a_single_local_worker_keeps_numbas_own_thread_count():
    with LocalExecutor(shared=None, workers=1) as executor:
        threads = dict(executor.map_unordered(numba_threads_in_worker, range(2)))

    assert executor.numba_threads == numba.config.NUMBA_NUM_THREADS
    assert set(threads.values()) == {numba.config.NUMBA_NUM_THREADS}


def test_a_batch_on_one_numba_thread_a_worker_gives_the_rows_of_numbas_own_and_says_so(
        tmp_path, numbas_own_threads):
    spec = write_spec(tmp_path / "spec")
    run = BatchRun(read_spec(spec), tmp_path / "out")
    started = []

    run.run(workers=2, on_start=lambda workers, threads: started.append((workers, threads)))

    assert started == [(2, 1)]
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["ran_on"] == {"workers": 2, "numba_threads": 1}
    # flown one by one here, on numba's own threads
    assert numba.get_num_threads() == numba.config.NUMBA_NUM_THREADS
    rows = read_rows(tmp_path / "out" / "results.csv")
    assert len(rows) == MISSIONS
    assert all(same_row(a, b) for a, b in zip(rows, rows_one_by_one(spec), strict=True))
