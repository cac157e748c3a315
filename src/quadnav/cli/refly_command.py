"""``quadnav refly``: fly one mission of a batch again, alone, and write its run folder with
figures, as ``quadnav fly`` does."""

from __future__ import annotations

import argparse
from pathlib import Path

from quadnav.cli.commands import command_help
from quadnav.cli.flight_args import add_strict_argument
from quadnav.cli.fly_command import write_mission
from quadnav.errors import QuadnavError
from quadnav.runfolder import check_output_folder
from quadnav.runs import REPORT


def refly(args: argparse.Namespace) -> int:
    """Rebuild the mission from the batch folder and fly it; exit codes as ``fly``."""
    from quadnav.batch.fly_one import fly_mission_spec, load_context
    from quadnav.batch.folder import read_record, recorded_spec
    from quadnav.batch.table import RESULTS_CSV, read_rows

    folder = Path(args.batch)
    record = read_record(folder)
    spec = recorded_spec(folder)
    missions = {mission.key: mission for mission in spec.missions()}
    key = args.mission
    if key not in missions:
        if not key.isdigit():
            raise QuadnavError(f"{key}: no mission of the batch in {folder} has this key; "
                               f"expected a mission_key or a row number of {RESULTS_CSV}")
        rows = read_rows(folder / RESULTS_CSV)
        if not 1 <= int(key) <= len(rows):
            raise QuadnavError(f"{key}: expected a row number of {folder / RESULTS_CSV}, "
                               f"from 1 to {len(rows)}")
        key = rows[int(key) - 1]["mission_key"]
    output = check_output_folder(args.output)
    context = load_context(spec)
    if context.fingerprint() != record["files"]:
        raise QuadnavError(f"{folder}: a map, gains or vehicle file of the batch changed "
                           "since it ran: the mission would not fly as it did")
    mission = fly_mission_spec(context, missions[key])
    return write_mission(mission, output, figures=not args.no_figures, html=args.html,
                         strict=args.strict)


def add_refly_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav refly`` on the top-level subparsers."""
    p = subparsers.add_parser(
        "refly", help=command_help("refly"),
        description="Rebuild one mission of a quadnav batch from its row and the batch's "
                    "settings (DIR/batch.json) and fly it alone, writing a run folder as "
                    f"quadnav fly does (metrics.json, figures, {REPORT}). Its metrics equal "
                    "the row's (but for wall times). Exit codes as quadnav fly.")
    p.add_argument("batch", metavar="BATCH_DIR", help="folder of a quadnav batch")
    p.add_argument("mission", metavar="KEY|ROW",
                   help="the row's mission_key, or its row number in results.csv (1: first)")
    p.add_argument("--no-figures", action="store_true", help=f"skip the figures and {REPORT}")
    p.add_argument("--html", action="store_true", help="also write DIR/view.html")
    add_strict_argument(p)
    p.add_argument("-o", "--output", default="refly", metavar="DIR",
                   help="folder to write into, created if needed (default: refly)")
    p.set_defaults(handler=refly)
