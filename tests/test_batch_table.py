"""The batch table's files: results.parquet is written a row group at a time and holds the
table of results.csv, whatever the number of rows."""

from __future__ import annotations

import pyarrow.parquet as pq
from batchtools import MISSIONS, rows_one_by_one, write_spec

from quadnav.batch.table import NAMES, read_rows, same_row, write_tables


def test_the_parquet_file_is_written_in_row_groups_and_equals_the_csv(tmp_path):
    rows = rows_one_by_one(write_spec(tmp_path / "spec"))

    assert write_tables(rows, tmp_path, group_rows=4) == ["results.parquet", "results.csv"]

    parquet = pq.ParquetFile(tmp_path / "results.parquet")
    assert [parquet.metadata.row_group(k).num_rows
            for k in range(parquet.num_row_groups)] == [4, MISSIONS - 4]
    table = read_rows(tmp_path / "results.csv")
    assert parquet.read().to_pylist() == table
    assert all(same_row(a, b, ignore=()) for a, b in zip(table, rows, strict=True))


def test_a_table_of_no_rows_is_a_parquet_file_of_the_schema_and_no_row(tmp_path):
    write_tables([], tmp_path)

    table = pq.read_table(tmp_path / "results.parquet")
    assert table.column_names == list(NAMES) and table.num_rows == 0
    assert read_rows(tmp_path / "results.csv") == []
