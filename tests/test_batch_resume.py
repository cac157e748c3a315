"""A real ``quadnav batch`` process stopped by Ctrl-C and by SIGTERM keeps every finished row;
running it again finishes the table, which equals the batch flown without a stop."""

from __future__ import annotations

import json
import signal
import subprocess
import time
from pathlib import Path

import pyarrow.parquet as pq
from batchtools import MISSIONS, rows_one_by_one, write_spec
from clitools import QUADNAV, run_here

from quadnav.batch.table import read_rows, same_row


def _start(spec: Path, out: Path) -> subprocess.Popen:
    return subprocess.Popen([*QUADNAV, "batch", str(spec), "--workers", "1", "--quiet", "-o",
                             str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _rows_written(path: Path) -> int:
    try:
        return path.read_text().count("\n") - 1
    except FileNotFoundError:
        return 0


def _stop_after(process: subprocess.Popen, journal: Path, rows: int, signum: int
                ) -> tuple[str, str]:
    """Send ``signum`` once the journal holds ``rows`` rows; returns stdout, stderr."""
    deadline = time.monotonic() + 120
    while _rows_written(journal) < rows and process.poll() is None:
        assert time.monotonic() < deadline, "the batch wrote no rows"
        time.sleep(0.01)
    process.send_signal(signum)
    return process.communicate(timeout=120)


def test_a_stopped_batch_keeps_its_rows_and_a_rerun_completes_the_same_table(tmp_path):
    spec = write_spec(tmp_path / "spec")
    out = tmp_path / "out"
    journal = out / "results.csv"

    _, stderr = _stop_after(first := _start(spec, out), journal, 2, signal.SIGINT)

    assert first.returncode == 130, stderr
    kept = read_rows(journal)
    assert 2 <= len(kept) < MISSIONS
    assert stderr.strip().splitlines()[-1] == (
        f"quadnav: stopped: kept {len(kept)} of {MISSIONS} missions in {journal}; run the "
        "same command again to resume")
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["finished"], summary["complete"]) == (len(kept), False)
    assert pq.read_table(out / "results.parquet").num_rows == len(kept)

    _, stderr = _stop_after(second := _start(spec, out), journal, len(kept) + 1,
                            signal.SIGTERM)

    assert second.returncode == 143, stderr
    more = read_rows(journal)
    assert len(kept) < len(more) < MISSIONS
    assert all(same_row(a, b, ignore=()) for a, b in zip(
        kept, (r for r in more if r["mission_key"] in {k["mission_key"] for k in kept}),
        strict=True))

    last = run_here("batch", spec, "--workers", "2", "--quiet", "-o", out)  # not stopped

    assert last.returncode == 0, last.stderr
    assert f"{MISSIONS} missions, {len(more)} already in {out}" in last.stdout
    rows = read_rows(journal)
    reference = rows_one_by_one(spec)  # flown here, one by one, without a stop
    assert [r["mission_key"] for r in rows] == [r["mission_key"] for r in reference]
    assert all(same_row(a, b) for a, b in zip(rows, reference, strict=True))
    assert json.loads((out / "summary.json").read_text())["complete"]
