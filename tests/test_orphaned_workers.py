"""A batch killed with SIGKILL (the OOM killer, a CI time-out) takes its workers with it: they
ignore stop signals, so before they ran on for good, about 220 MB each."""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

import pytest
from clitools import QUADNAV

#: Longest wait for the workers to start, or to leave once the batch is gone, s: a bound on
#: a busy machine, not a measured time (they leave within a second).
PATIENCE = 120.0


def children(pid: int) -> list[int]:
    """The processes whose parent is ``pid``."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                found.append(int(entry.name))
    return found


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def wait_for(condition, patience: float = PATIENCE) -> bool:
    deadline = time.monotonic() + patience
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.2)
    return condition()


def test_workers_leave_when_the_batch_is_killed(tmp_path):
    batch = subprocess.Popen([*QUADNAV, "batch", "forest", "--seeds", "500", "--workers", "2",
                              "--quiet", "-o", str(tmp_path / "b")],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                             start_new_session=True)
    workers: list[int] = []
    try:
        assert wait_for(lambda: len(children(batch.pid)) >= 2), "the workers never started"
        workers = children(batch.pid)
        os.kill(batch.pid, signal.SIGKILL)
        batch.wait()
        assert wait_for(lambda: not any(map(alive, workers))), \
            f"workers left running: {[w for w in workers if alive(w)]}"
    finally:
        for pid in [batch.pid, *workers]:
            if alive(pid):
                os.kill(pid, signal.SIGKILL)


@pytest.mark.parametrize("signum", [signal.SIGHUP, signal.SIGTERM])
def test_a_stopped_process_group_says_one_line_and_nothing_else(tmp_path, signum):
    """A closed terminal or a job control stop reaches the batch, its workers and
    multiprocessing's resource tracker at once: the batch's one line, no worker's traceback,
    no resource tracker's "process died unexpectedly", no "leaked semaphore"."""
    batch = subprocess.Popen([*QUADNAV, "batch", "forest", "--seeds", "500", "--workers", "2",
                              "--quiet", "-o", str(tmp_path / "b")],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                             start_new_session=True)
    try:
        assert wait_for(lambda: len(children(batch.pid)) >= 3), "the workers never started"
        os.killpg(batch.pid, signum)
        _, errors = batch.communicate(timeout=PATIENCE)
    finally:
        if batch.poll() is None:
            os.killpg(batch.pid, signal.SIGKILL)
    assert batch.returncode == 128 + signum
    lines = errors.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("quadnav: stopped: kept "), errors
