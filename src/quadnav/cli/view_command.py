"""``quadnav view``: a run folder as one interactive 3D page to open in a browser."""

from __future__ import annotations

import argparse

from quadnav.cli.args import output_path
from quadnav.cli.commands import command_help
from quadnav.runs import VIEW_PAGE, read_run
from quadnav.viz.html_viewer import write_viewer


def view(args: argparse.Namespace) -> int:
    """Check the page's name, read the run folder, write its page; print where it went.
    Exit 2 on bad input, nothing written."""
    from quadnav.report.html_report import check_report_path

    output = check_report_path(args.output) if args.output else None
    run = read_run(args.folder)
    written = write_viewer(run, output or run.folder / VIEW_PAGE)
    print(f"wrote {written}")
    return 0


def add_view_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav view`` on the top-level subparsers."""
    p = subparsers.add_parser(
        "view", help=command_help("view"),
        description="Write one self-contained HTML page showing the run in DIR (written by "
                    "quadnav fly -o DIR or quadnav track REF -o DIR): the map, the explored "
                    "tree, the path, the trajectory coloured by speed, the flown track, a "
                    "time slider moving the drone along the flight, and the metrics. Drag to "
                    "rotate, wheel to zoom. The page needs no network and no files beside it; "
                    "open it in any browser.")
    p.add_argument("folder", metavar="DIR", help="a folder written by quadnav fly or quadnav track")
    p.add_argument("-o", "--output", type=output_path, metavar="FILE",
                   help=f"the page to write, ending in .html (default: DIR/{VIEW_PAGE})")
    p.set_defaults(handler=view)
