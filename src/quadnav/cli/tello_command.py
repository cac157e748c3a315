"""``quadnav tello``: the DJI Ryze Tello — an emulator on this computer, flights on the drone.

Each subcommand is one ``add_*`` function in :data:`SUBCOMMANDS`; it registers its parser
on the ``tello`` subparsers and sets ``handler`` (called with the parsed arguments, returns
the exit code).

* ``quadnav tello emulate`` — run a Tello SDK 2.0 emulator (:mod:`quadnav.hardware.emulator.server`)
  in the foreground until Ctrl-C.
* ``quadnav tello fly`` — plan, check and fly a mission on a Tello
  (:mod:`quadnav.cli.tello_fly_command`).
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable

from quadnav.cli.args import add_seed_argument, coordinate, heading_degrees, time_scale
from quadnav.cli.commands import command_help
from quadnav.cli.tello_fly_command import add_tello_fly_command
from quadnav.hardware.sdk import DEFAULT_HOST
from quadnav.limits import COORDINATE, HEADING_DEGREES, TIME_SCALE


def emulate(args: argparse.Namespace) -> int:
    """Run the emulator until Ctrl-C (KeyboardInterrupt: exit 130 via the main entry)."""
    from quadnav.hardware.emulator.server import Faults, TelloEmulator

    faults = Faults.real_tello() if args.imperfect else None
    with TelloEmulator(host=args.host, start=tuple(args.start), yaw=math.radians(args.yaw),
                       time_scale=args.time_scale, faults=faults, seed=args.seed,
                       truth=args.truth) as emulator:
        imperfect = f", a real Tello's imperfections (seed {args.seed})" if faults else ""
        truth = f", its true track written to {args.truth}" if args.truth else ""
        print(f"Emulated Tello at {emulator.host} (UDP 8889, state to the client's 8890), "
              f"start {tuple(args.start)} m, yaw {args.yaw:g} deg, time scale "
              f"{args.time_scale:g}{imperfect}{truth}. Connect with djitellopy "
              f"Tello(host={emulator.host!r}). Ctrl-C to stop.", flush=True)
        while True:
            time.sleep(1.0)


def add_emulate_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav tello emulate``."""
    parser = subparsers.add_parser(
        "emulate", help="run a Tello SDK 2.0 emulator for djitellopy until Ctrl-C",
        description="Run a Tello SDK 2.0 emulator that the djitellopy client drives as if it "
                    "were the drone: commands on UDP 8889 at HOST, state packets at 10 Hz to "
                    "the client's port 8890, motion flown by quadnav's simulator in real time. "
                    "The emulator lives in its own Linux network namespace joined to this one "
                    "by a virtual Ethernet pair, so it needs root (or a user namespace: "
                    "unshare -rn).")
    parser.add_argument("--host", default=DEFAULT_HOST, metavar="IP",
                        help=f"IPv4 address of the emulated drone (default: {DEFAULT_HOST}); "
                             "this computer gets the other address of its /31 pair")
    parser.add_argument("--start", nargs=3, type=coordinate, default=(0.0, 0.0, 0.0),
                        metavar=("X", "Y", "Z"),
                        help="world position of the drone on the ground before takeoff, each "
                             f"{COORDINATE.describe()} (default: 0 0 0)")
    parser.add_argument("--yaw", type=heading_degrees, default=0.0, metavar="DEG",
                        help="world heading of the drone's nose at power-on, counter-clockwise "
                             f"from world x, {HEADING_DEGREES.describe()} (default: 0)")
    parser.add_argument("--time-scale", type=time_scale, default=1.0, metavar="K",
                        help=f"emulated seconds per wall-clock second, {TIME_SCALE.describe()} "
                             "(default: 1, real time)")
    parser.add_argument("--imperfect", action="store_true",
                        help="fly as a real Tello does: moves that end about 2 cm off per "
                             "axis, a takeoff height of 0.7-0.9 m, vgx/vgy a unit off a quarter "
                             "of the time, one reply in a hundred lost (drawn from --seed)")
    add_seed_argument(parser, "seed of the imperfections")
    parser.add_argument("--truth", metavar="FILE",
                        help="write the drone's true track to FILE as it flies (CSV "
                             "unix_time_s,x,y,z: UNIX seconds and world metres, every 20 ms "
                             "of emulated time), for 'quadnav tello fly --truth FILE'")
    parser.set_defaults(handler=emulate)


#: The ``quadnav tello`` subcommands, in the order ``--help`` lists them.
SUBCOMMANDS: list[Callable[[argparse._SubParsersAction], None]] = [
    add_emulate_command, add_tello_fly_command]


def add_tello_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav tello`` and its subcommands (:data:`SUBCOMMANDS`)."""
    tello = subparsers.add_parser(
        "tello", help=command_help("tello"),
        description="Work with a DJI Ryze Tello through its SDK 2.0 (the djitellopy client).")
    commands = tello.add_subparsers(dest="tello_command", metavar="SUBCOMMAND", required=True)
    for add in SUBCOMMANDS:
        add(commands)
