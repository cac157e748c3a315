"""``quadnav batch`` on a real local Ray (``ray.init(num_cpus=2)``) gives the same table as
the missions flown one by one in this process."""

from __future__ import annotations

import pytest
from batchtools import MISSIONS, rows_one_by_one, write_spec
from clitools import assert_user_error, run_here

from quadnav.batch.grid import read_spec
from quadnav.batch.run import BatchRun
from quadnav.batch.table import read_rows, same_row

pytest.importorskip("ray", reason="Ray is an optional extra: pip install 'quadnav[ray]'")


def test_a_batch_on_a_local_ray_gives_the_table_of_a_local_run(tmp_path):
    spec = write_spec(tmp_path / "spec")
    run = BatchRun(read_spec(spec), tmp_path / "out")

    run.run(workers=2, ray=True)  # a local Ray started for the run: ray.init(num_cpus=2)

    rows = read_rows(tmp_path / "out" / "results.csv")
    assert len(rows) == MISSIONS
    assert all(same_row(a, b) for a, b in zip(rows, rows_one_by_one(spec), strict=True))



def test_a_ray_address_where_nothing_answers_is_one_line_and_nothing_is_written(tmp_path):
    result = run_here("batch", "empty", "--seeds", "1", "--ray", "127.0.0.1:1", "-o",
                      tmp_path / "out")

    assert_user_error(result, "--ray 127.0.0.1:1: cannot reach the Ray cluster's head")
    assert not (tmp_path / "out").exists()
