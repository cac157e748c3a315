"""A batch folder: ``batch.json`` (what the batch is), the journal of finished rows and the
outputs written from them.

``batch.json`` holds the spec with every path resolved and every default filled in, what
its files gave (the vehicle, the gains, a hash of each map) and the table's columns. A
re-run into the same folder must be the same batch: it then skips the missions already in
the journal; any other batch is refused (or, with ``restart``, the folder's batch files
are replaced).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from quadnav.batch.fly_one import BatchContext
from quadnav.batch.grid import BatchSpec, MissionSpec, parse_spec
from quadnav.batch.summary import SUMMARY_JSON, summary, write_summary
from quadnav.batch.summary_page import SUMMARY_HTML, write_summary_page
from quadnav.batch.table import NAMES, RESULTS_CSV, RESULTS_PARQUET, read_rows, write_tables
from quadnav.errors import QuadnavError
from quadnav.files import atomic_output

BATCH_JSON = "batch.json"
#: Every file a batch writes into its folder.
BATCH_FILES = (BATCH_JSON, RESULTS_CSV, RESULTS_PARQUET, SUMMARY_JSON, SUMMARY_HTML)


def batch_record(spec: BatchSpec, context: BatchContext) -> dict[str, Any]:
    """What ``batch.json`` holds for ``spec`` loaded as ``context`` (as read back from
    JSON, so that records compare equal)."""
    record = {"spec": spec.table(), "files": context.fingerprint(), "columns": list(NAMES)}
    return json.loads(json.dumps(record))


def _difference(old: dict[str, Any], new: dict[str, Any]) -> str:
    """What first differs between two batch records, in words."""
    if old.get("columns") != new["columns"]:
        return "its table has other columns (another quadnav version)"
    for key, value in new["spec"].items():
        if old.get("spec", {}).get(key) != value:
            return f"its {key} differ" if key.endswith("s") else f"its {key} differs"
    for key in new["files"]:
        if old.get("files", {}).get(key) != new["files"][key]:
            return f"a {key.rstrip('s')} file changed since"
    return "its spec differs"


def read_record(folder: Path) -> dict[str, Any]:
    """``folder``/batch.json; QuadnavError if it is missing or not a batch record."""
    path = folder / BATCH_JSON
    try:
        record = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise QuadnavError(f"{folder}: not a quadnav batch folder (no {BATCH_JSON}); run "
                           "quadnav batch -o DIR first") from None
    except OSError as error:
        raise QuadnavError(f"{path}: cannot read: {error.strerror}") from None
    except json.JSONDecodeError as error:
        raise QuadnavError(f"{path}:{error.lineno}: not valid JSON: {error.msg}") from None
    if not isinstance(record, dict) or not isinstance(record.get("spec"), dict):
        raise QuadnavError(f"{path}: expected a batch record with a spec")
    return record


def recorded_spec(folder: Path) -> BatchSpec:
    """The spec of the batch in ``folder`` (from batch.json)."""
    return parse_spec(read_record(folder)["spec"], folder, str(folder / BATCH_JSON))


def finished_rows(folder: Path, record: dict[str, Any], restart: bool
                  ) -> list[dict[str, Any]]:
    """The rows already finished in ``folder`` for the batch of ``record`` (none for a new
    folder, or with ``restart``). Writes nothing.

    Raises:
        QuadnavError: ``folder`` holds another batch (and not ``restart``), or its journal
            is not readable.
    """
    if restart or not ((folder / BATCH_JSON).exists() or (folder / RESULTS_CSV).exists()):
        return []
    old = read_record(folder) if (folder / BATCH_JSON).exists() else {}
    if old != record:
        raise QuadnavError(
            f"{folder}: holds another batch ({_difference(old, record)}); run the same batch "
            "again to resume it, or use another -o DIR, or --restart to start over")
    return read_rows(folder / RESULTS_CSV) if (folder / RESULTS_CSV).exists() else []


def begin(folder: Path, record: dict[str, Any], restart: bool) -> None:
    """Make ``folder`` (created if needed) hold the batch of ``record``: with ``restart``,
    the files of the batch it held are removed first; ``batch.json`` is written unless it
    is there (checked by :func:`finished_rows`)."""
    folder.mkdir(parents=True, exist_ok=True)
    if restart:
        for name in BATCH_FILES:
            (folder / name).unlink(missing_ok=True)
    if not (folder / BATCH_JSON).exists():
        with atomic_output(folder / BATCH_JSON) as tmp:
            tmp.write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")


def ordered_rows(missions: Sequence[MissionSpec], rows: dict[str, dict[str, Any]]
                 ) -> list[dict[str, Any]]:
    """The finished ``rows`` (by mission key) in the order of ``missions``."""
    return [rows[m.key] for m in missions if m.key in rows]


def write_outputs(folder: Path, rows: list[dict[str, Any]], expected: int,
                  ran_on: dict[str, int] | None = None) -> list[str]:
    """Write the tables, ``summary.json`` and ``summary.html`` of ``rows`` (``expected``:
    the batch's size; ``ran_on``: see :func:`~.summary.summary`); returns the file names
    written."""
    written = write_tables(rows, folder)
    content = summary(rows, expected, ran_on)
    write_summary(content, folder / SUMMARY_JSON)
    write_summary_page(content, rows, folder)
    return [*written, SUMMARY_JSON, SUMMARY_HTML]
