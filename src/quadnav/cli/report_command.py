"""``quadnav report``: one self-contained HTML report over one or more run folders."""

from __future__ import annotations

import argparse
from pathlib import Path

from quadnav.cli.args import output_path
from quadnav.cli.commands import command_help
from quadnav.runs import REPORT, read_run


def report(args: argparse.Namespace) -> int:
    """Read every folder, then write the report; exit 0 (2 on bad input, nothing
    written)."""
    from quadnav.report.html_report import write_report

    default = Path(args.folders[0]) / REPORT if len(args.folders) == 1 else Path(REPORT)
    runs = [read_run(folder) for folder in args.folders]
    written = write_report(runs, args.output or default)
    print(f"wrote {written} ({len(runs)} run{'s' if len(runs) > 1 else ''})")
    return 0


def add_report_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav report`` on the top-level subparsers."""
    p = subparsers.add_parser(
        "report", help=command_help("report"),
        description="One self-contained HTML file (images embedded, no external links) with "
                    "a section per run folder: the map and outcome, the explored tree with "
                    "the path in red, desired against actual position and velocity, the "
                    "tracking error, the metrics and every parameter used; with several "
                    "folders, an overview table first. Figures are the folder's PNG files, "
                    "or drawn from its data when it has none (quadnav fly --no-figures). "
                    f"quadnav fly and track write DIR/{REPORT} themselves. Exit 2 on bad input.")
    p.add_argument("folders", nargs="+", metavar="DIR", help="quadnav fly or track output folders")
    p.add_argument("-o", "--output", type=output_path, metavar="FILE",
                   help=f"the report to write, ending in .html (default: DIR/{REPORT} for one "
                        f"folder, {REPORT} in the current folder for several)")
    p.set_defaults(handler=report)
