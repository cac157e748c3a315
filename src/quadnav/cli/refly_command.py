"""``quadnav refly``: fly a run folder's mission again (its mission.toml), or one mission of
a batch, alone, and write its run folder with figures, as ``quadnav fly`` does."""

from __future__ import annotations

import argparse
from pathlib import Path

from quadnav.cli.args import output_path
from quadnav.cli.commands import command_help
from quadnav.cli.flight_args import add_strict_argument
from quadnav.cli.fly_command import write_mission
from quadnav.errors import QuadnavError
from quadnav.missionconfig import MISSION_FILE, MissionConfig, read_run_mission
from quadnav.runfolder import check_output_folder
from quadnav.runs import REPORT


def refly(args: argparse.Namespace) -> int:
    """Rebuild the mission from the run or batch folder and fly it; exit codes as ``fly``."""
    folder = Path(args.folder)
    if args.mission is None:
        if not (folder / MISSION_FILE).is_file():
            raise QuadnavError(f"{folder}: no {MISSION_FILE}: expected a run folder of quadnav "
                               "fly or refly, or a batch folder and a mission's KEY|ROW")
        config = read_run_mission(folder / MISSION_FILE)
        output = check_output_folder(args.output)
        mission = config.fly()
    else:
        config, flown = _batch_mission(folder, args.mission)
        output = check_output_folder(args.output)
        mission = flown()
    return write_mission(mission, config, output, figures=not args.no_figures, html=args.html,
                         strict=args.strict)


def _batch_mission(folder: Path, key: str):
    """The config of the mission ``key`` (a mission_key or a row number) of the batch in
    ``folder``, and a function flying it."""
    from quadnav.batch.fly_one import fly_mission_spec, load_context, mission_config
    from quadnav.batch.folder import batch_rows, current_record, read_record, recorded_spec
    from quadnav.batch.table import RESULTS_CSV

    record = current_record(read_record(folder))
    spec = recorded_spec(folder)
    missions = {mission.key: mission for mission in spec.missions()}
    if key not in missions:
        if not key.isdigit():
            raise QuadnavError(f"{key}: no mission of the batch in {folder} has this key; "
                               f"expected a mission_key or a row number of {RESULTS_CSV}")
        rows = batch_rows(folder, spec)
        if not 1 <= int(key) <= len(rows):
            raise QuadnavError(f"{key}: expected a row number of {folder / RESULTS_CSV}, "
                               f"from 1 to {len(rows)}")
        key = rows[int(key) - 1]["mission_key"]
    context = load_context(spec)
    if context.fingerprint() != record["files"]:
        raise QuadnavError(f"{folder}: a map, gains or vehicle file of the batch changed "
                           "since it ran: the mission would not fly as it did")
    config: MissionConfig = mission_config(spec.fixed, missions[key])
    return config, lambda: fly_mission_spec(context, missions[key])


def add_refly_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav refly`` on the top-level subparsers."""
    p = subparsers.add_parser(
        "refly", help=command_help("refly"),
        description=f"Fly a run folder's mission again (its {MISSION_FILE}, as quadnav fly "
                    "--mission does), or rebuild one mission of a quadnav batch from its row "
                    "and the batch's settings (DIR/batch.json) and fly it alone; either way "
                    "write a run folder as quadnav fly does (metrics.json, "
                    f"{MISSION_FILE}, figures, {REPORT}). Its metrics equal the run's or the "
                    "row's (but for wall times). Exit codes as quadnav fly.")
    p.add_argument("folder", metavar="DIR",
                   help=f"a run folder (with its {MISSION_FILE}) or a quadnav batch folder")
    p.add_argument("mission", metavar="KEY|ROW", nargs="?",
                   help="for a batch folder: the row's mission_key, or its row number in "
                        "results.csv (1: first)")
    p.add_argument("--no-figures", action="store_true", help=f"skip the figures and {REPORT}")
    p.add_argument("--html", action="store_true", help="also write DIR/view.html")
    add_strict_argument(p)
    p.add_argument("-o", "--output", type=output_path, default="refly", metavar="DIR",
                   help="folder to write into, created if needed (default: refly)")
    p.set_defaults(handler=refly)
