"""``quadnav compare``: the leaderboard of a batch's contenders (controllers, planners,
trajectories, winds ...), with intervals and which differences are significant."""

from __future__ import annotations

import argparse
from pathlib import Path

from quadnav.batch.compare import ALPHA, AXES, compare, write_tables
from quadnav.batch.compare import choose_axes as chosen_axes
from quadnav.batch.compare_page import (
    comparison_text,
    leaderboard_rows,
    untimed_text,
    write_compare_page,
)
from quadnav.batch.folder import BATCH_JSON, batch_rows
from quadnav.batch.table import RESULTS_CSV
from quadnav.cli.commands import command_help
from quadnav.errors import QuadnavError


def _rows(folder: Path) -> list[dict]:
    """The finished rows of the batch in ``folder``; QuadnavError when it is not a batch
    folder or holds no finished mission."""
    if not (folder / BATCH_JSON).is_file():
        raise QuadnavError(f"{folder}: not a quadnav batch folder (no {BATCH_JSON}); expected "
                           "the -o DIR of quadnav batch")
    rows = batch_rows(folder) if (folder / RESULTS_CSV).is_file() else []
    if not rows:
        raise QuadnavError(f"{folder}: the batch has no finished mission yet; run it first")
    return rows


def _table(header: list[str], rows: list[list[str]]) -> list[str]:
    """Text lines of a table, each column as wide as its widest cell."""
    widths = [max(len(row[k]) for row in [header, *rows]) for k in range(len(header))]
    return ["  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=True)
                      ).rstrip() for row in [header, *rows]]


def compare_batch(args: argparse.Namespace) -> int:
    """Print the leaderboard and write compare.csv, .json, .html and .png into the batch
    folder."""
    folder = Path(args.folder)
    leaderboard(folder, _rows(folder), args.by)
    return 0


def leaderboard(folder: Path, rows: list[dict], by: list[str] | None) -> None:
    """Print the leaderboard of the batch ``rows`` in ``folder`` by the axes ``by`` (None:
    those that vary) and write compare.csv, .json, .html and .png there."""
    by = chosen_axes(rows, by, folder)
    result = compare(rows, by)
    contenders = result["contenders"]
    print(f"compared by {', '.join(by)}: {len(contenders)} contenders, {len(rows)} missions; "
          "a mission is paired with those that differ only in the contender")
    if note := untimed_text(result):
        print(note)
    print("\n".join(_table(*leaderboard_rows(result))))
    tests = result["comparisons"]
    significant = sorted((c for c in tests if c["significant"]), key=lambda c: c["p_holm"])
    print(f"significant differences at alpha {ALPHA:g}, Holm-corrected over "
          f"{sum(bool(c['pairs']) for c in tests)} tests "
          "(McNemar's exact test on success, Wilcoxon's signed-rank test on the rest): "
          f"{len(significant) or 'none'}")
    for c in significant:
        print(f"  {c['a']} vs {c['b']}: {comparison_text(c)} (p {c['p']:.2g}, Holm "
              f"{c['p_holm']:.2g})")
    written = [*write_tables(result, folder), *write_compare_page(result, folder)]
    print("wrote " + ", ".join(str(folder / name) for name in written))


def add_compare_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav compare`` on the top-level subparsers."""
    p = subparsers.add_parser(
        "compare", help=command_help("compare"),
        description="The leaderboard of a quadnav batch folder: per contender (each "
                    "controller, planner, trajectory method or class, wind ... the batch "
                    "flew, or each combination when several vary), the success rate with "
                    "its Wilson 95 % interval and the median and quartiles of the time to "
                    "goal, tracking error, margin kept, rotor energy and compute time; and "
                    "which differences are significant (missions paired by every other grid "
                    "value: McNemar's exact test on success, Wilcoxon's signed-rank test on "
                    f"the rest, Holm-corrected, alpha {ALPHA:g}). Prints it and writes "
                    "DIR/compare.csv, compare.json, compare.html and compare.png. Exit 2 for "
                    "a folder that is not a batch or a batch with a single contender.")
    p.add_argument("folder", metavar="DIR", help="a quadnav batch folder (its -o DIR)")
    p.add_argument("--by", nargs="+", choices=tuple(AXES), metavar="AXIS",
                   help=f"the axes whose values are the contenders, of {', '.join(AXES)} "
                        "(default: every one of controller, planner, method or reference, "
                        "wind and gains that varies)")
    p.set_defaults(handler=compare_batch)
