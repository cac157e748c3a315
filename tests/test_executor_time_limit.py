"""A job that runs past its time limit on a local worker (an endless loop in a plug-in) is
stopped: its worker is killed and replaced, its result is ``lost(item, reason)`` at once,
not run again, and the other jobs and the executor go on. The worker's warm-up does not
count against its first job's limit."""

from __future__ import annotations

import time

import pytest

from quadnav.batch.executor import LocalExecutor, TimeLimitError


def sleep_for(shared: object, seconds: float) -> float:
    """A job: sleep ``seconds`` s, then return them."""
    time.sleep(seconds)
    return seconds


def slow_warm_up(shared: object) -> None:
    """A warm-up longer than the tests' time limit of 1 s."""
    time.sleep(2)


def given_up(item: float, reason: str) -> str:
    return f"{item:g}: {reason}"


def test_a_job_past_its_time_limit_is_stopped_and_lost_and_the_others_go_on():
    with LocalExecutor(shared=None, workers=2) as executor:
        results = dict(executor.map_unordered(sleep_for, [0, 1000, 0.1, 0], given_up,
                                              time_limit=1))
        assert results == {0: 0, 1: "1000: ran longer than the 1 s limit; stopped",
                           2: 0.1, 3: 0}
        assert executor.retried == 0  # stopped, not run again
        again = executor.map_unordered(sleep_for, [0.2, 0.3], time_limit=1)
        assert sorted(again) == [(0, 0.2), (1, 0.3)]  # its new worker works


def test_a_job_past_its_time_limit_is_an_error_without_a_lost_result():
    with LocalExecutor(shared=None, workers=1) as executor, pytest.raises(
            TimeLimitError, match=r"^a job ran longer than the 0\.5 s limit; stopped$"):
        list(executor.map_unordered(sleep_for, [1000], time_limit=0.5))


def test_the_warm_up_does_not_count_against_a_jobs_time_limit():
    with LocalExecutor(shared=None, warm_up=slow_warm_up, workers=1) as executor:
        assert list(executor.map_unordered(sleep_for, [0, 0], given_up, time_limit=1)) == [
            (0, 0), (1, 0)]
