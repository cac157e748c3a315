"""Entry point of the ``quadnav`` command.

Exit codes: 0 success; 1 a flight or search that failed (see each command); 2 bad
input (a malformed map, a bad flag, a point in a block), reported as one line on
stderr with no traceback; 128 + the signal number when stopped by Ctrl-C (130), SIGTERM
(143) or SIGHUP (129) (see :mod:`quadnav.cli.launch`).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Sequence

from quadnav import __version__
from quadnav.cli.animate_command import add_animate_command
from quadnav.cli.batch_command import add_batch_command
from quadnav.cli.blender_command import add_blender_command
from quadnav.cli.fly_command import add_fly_command
from quadnav.cli.kino_command import add_kino_command
from quadnav.cli.launch import report_stop
from quadnav.cli.map_commands import add_map_commands
from quadnav.cli.plan_command import add_plan_command
from quadnav.cli.refly_command import add_refly_command
from quadnav.cli.report_command import add_report_command
from quadnav.cli.tello_command import add_tello_command
from quadnav.cli.track_command import add_track_command
from quadnav.cli.traj_command import add_traj_command
from quadnav.cli.tune_command import add_tune_command
from quadnav.cli.view_command import add_view_command
from quadnav.cli.worlds_command import add_references_command, add_worlds_command
from quadnav.errors import QuadnavError

EXIT_USAGE = 2


class _OneLineErrorParser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors are one line on stderr, exit code 2."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The full ``quadnav`` argument parser."""
    parser = _OneLineErrorParser(
        prog="quadnav",
        description="Plan, smooth, fly and show quadrotor flights through 3D maps of boxes.",
    )
    parser.add_argument("--version", action="version", version=f"quadnav {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    add_fly_command(commands)
    add_track_command(commands)
    add_batch_command(commands)
    add_refly_command(commands)
    add_tune_command(commands)
    add_animate_command(commands)
    add_blender_command(commands)
    add_map_commands(commands)
    add_plan_command(commands)
    add_report_command(commands)
    add_traj_command(commands)
    add_view_command(commands)
    add_kino_command(commands)
    add_worlds_command(commands)
    add_references_command(commands)
    add_tello_command(commands)
    return parser


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"quadnav: warning: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code (also used by the console script)."""
    warnings.showwarning = _one_line_warning
    try:  # a stop while the parser is built or reads the flags is a stop too
        args = build_parser().parse_args(argv)
        return args.handler(args)
    except QuadnavError as error:
        print(f"quadnav: error: {error}", file=sys.stderr)
        return EXIT_USAGE
    except (KeyboardInterrupt, ImportError) as error:  # a stop during a lazy import too
        return report_stop(error)


if __name__ == "__main__":
    sys.exit(main())
