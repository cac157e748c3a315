"""A batch folder: ``batch.json`` (what the batch is), the journal of finished rows and the
outputs written from them.

``batch.json`` holds the spec with every path resolved and every default filled in, what
its files gave (the vehicle, the gains, a hash of each map and plug-in file) and the
table's columns. A re-run into the same folder must be the same batch: it then skips the
missions already in the journal; any other batch is refused (or, with ``restart``, the
folder's batch files are replaced).

A folder written before the stall rule is a batch of ``stall = 0`` (each search ran its
whole ``improve`` budget). A folder written before rows had the flown time to goal
(:data:`~quadnav.batch.table.UNTIMED_NAMES`; its rows keep it empty), before the simulation
had seeds of its own and rows said which plan they flew
(:data:`~quadnav.batch.table.PREVIOUS_NAMES`), or before
that, before controllers, methods, references and wind classes were values of the grid
(:data:`~quadnav.batch.table.EARLIER_NAMES`), is the same batch as the one its spec now
reads as (:func:`current_record`): it resumes, and its ``batch.json`` and ``results.csv``
are then rewritten in today's form (:func:`begin`).

``plans/`` holds the plans the batch's missions flew (:mod:`~quadnav.batch.stages`), so
that a resumed batch plans none again.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from quadnav.batch.fly_one import BatchContext
from quadnav.batch.grid import NO_REFERENCE, BatchSpec, MissionSpec, spec_from_table
from quadnav.batch.summary import SUMMARY_JSON, summary, write_summary
from quadnav.batch.summary_page import SUMMARY_HTML, write_summary_page
from quadnav.batch.table import (
    EARLIER_NAMES,
    NAMES,
    PREVIOUS_NAMES,
    RESULTS_CSV,
    RESULTS_PARQUET,
    UNTIMED_NAMES,
    read_rows,
    write_csv,
    write_tables,
)
from quadnav.control.registry import DEFAULT_CONTROLLER
from quadnav.errors import QuadnavError
from quadnav.files import atomic_output
from quadnav.planning.stall import DEFAULT_STALL_FRACTION

BATCH_JSON = "batch.json"
#: Every file a batch writes into its folder.
BATCH_FILES = (BATCH_JSON, RESULTS_CSV, RESULTS_PARQUET, SUMMARY_JSON, SUMMARY_HTML)
#: The folder of the batch's plans (:class:`~quadnav.batch.stages.StageCache`).
PLANS = "plans"


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


def current_record(record: dict[str, Any]) -> dict[str, Any]:
    """``record`` as written today: one written before the stall rule (no ``stall`` in its
    spec) searched for its whole ``improve`` budget, ``stall = 0``; one written before rows
    had the time to goal (its columns :data:`UNTIMED_NAMES`) or before the simulation had
    seeds of its own (:data:`PREVIOUS_NAMES`, its seeds seeding both) is today's with
    today's columns; one written before controllers, methods,
    references and wind classes were values of the grid (its columns :data:`EARLIER_NAMES`)
    had one ``method``, flew the default controller with no reference, and kept the gains of
    that controller alone; any other record as it is."""
    if "stall" not in record["spec"]:
        record = record | {"spec": record["spec"] | {"stall": 0, "stall_fraction":
                                                     DEFAULT_STALL_FRACTION}}
    if record.get("columns") in (list(UNTIMED_NAMES), list(PREVIOUS_NAMES)):
        return record | {"columns": list(NAMES)}
    if record.get("columns") != list(EARLIER_NAMES):
        return record
    spec = dict(record["spec"])
    spec["methods"] = [spec.pop("method")]
    spec |= {"controllers": [DEFAULT_CONTROLLER], "references": [NO_REFERENCE]}
    files = dict(record["files"])
    files["gains"] = {DEFAULT_CONTROLLER: files["gains"]}
    return {"spec": spec, "files": files, "columns": list(NAMES)}


def recorded_spec(folder: Path) -> BatchSpec:
    """The spec of the batch in ``folder`` (from batch.json)."""
    return spec_from_table(current_record(read_record(folder))["spec"], folder,
                           str(folder / BATCH_JSON))


def batch_rows(folder: Path, spec: BatchSpec | None = None) -> list[dict[str, Any]]:
    """The rows finished in the batch ``folder`` (its spec ``spec``, None: read from
    batch.json), as today's table has them (:func:`~quadnav.batch.table.read_rows`)."""
    spec = recorded_spec(folder) if spec is None else spec
    return read_rows(folder / RESULTS_CSV, spec.missions())


def finished_rows(folder: Path, record: dict[str, Any], missions: Sequence[MissionSpec],
                  restart: bool) -> list[dict[str, Any]]:
    """The rows already finished in ``folder`` for the batch of ``record`` and its
    ``missions`` (none for a new folder, or with ``restart``). Writes nothing.

    Raises:
        QuadnavError: ``folder`` holds another batch (and not ``restart``), or its journal
            is not readable.
    """
    if restart or not ((folder / BATCH_JSON).exists() or (folder / RESULTS_CSV).exists()):
        return []
    old = current_record(read_record(folder)) if (folder / BATCH_JSON).exists() else {}
    if old != record:
        raise QuadnavError(
            f"{folder}: holds another batch ({_difference(old, record)}); run the same batch "
            "again to resume it, or use another -o DIR, or --restart to start over")
    if not (folder / RESULTS_CSV).exists():
        return []
    return read_rows(folder / RESULTS_CSV, missions)


def begin(folder: Path, record: dict[str, Any], restart: bool,
          rows: Sequence[dict[str, Any]]) -> None:
    """Make ``folder`` (created if needed) hold the batch of ``record``, whose finished
    ``rows`` it holds (:func:`finished_rows`): with ``restart``, the files and plans of the
    batch it held are removed first; ``batch.json`` is written unless it is there, and with
    ``results.csv`` written again in today's form when the folder was written before
    (:func:`current_record`)."""
    folder.mkdir(parents=True, exist_ok=True)
    if restart:
        for name in BATCH_FILES:
            (folder / name).unlink(missing_ok=True)
        shutil.rmtree(folder / PLANS, ignore_errors=True)
    if (folder / BATCH_JSON).exists() and read_record(folder) == record:
        return
    if (folder / RESULTS_CSV).exists():
        write_csv(rows, folder / RESULTS_CSV)
    with atomic_output(folder / BATCH_JSON) as tmp:
        tmp.write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")


def ordered_rows(missions: Sequence[MissionSpec], rows: dict[str, dict[str, Any]]
                 ) -> list[dict[str, Any]]:
    """The finished ``rows`` (by mission key) in the order of ``missions``."""
    return [rows[m.key] for m in missions if m.key in rows]


def write_outputs(folder: Path, rows: list[dict[str, Any]], expected: int,
                  ran_on: dict[str, int] | None = None, retried: int | None = None
                  ) -> list[str]:
    """Write the tables, ``summary.json`` and ``summary.html`` of ``rows`` (``expected``:
    the batch's size; ``ran_on``, ``retried``: see :func:`~.summary.summary`); returns the
    file names written."""
    written = write_tables(rows, folder)
    content = summary(rows, expected, ran_on, retried)
    write_summary(content, folder / SUMMARY_JSON)
    write_summary_page(content, rows, folder)
    return [*written, SUMMARY_JSON, SUMMARY_HTML]
