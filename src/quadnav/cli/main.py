"""Entry point of the ``quadnav`` command.

Exit codes: 0 success; 1 a flight or search that failed (see each command); 2 bad
input (a malformed map, a bad flag, a point in a block), reported as one line on
stderr with no traceback; 128 + the signal number when stopped by Ctrl-C (130), SIGTERM
(143) or SIGHUP (129) (see :mod:`quadnav.cli.launch`).
"""

from __future__ import annotations

import argparse
import importlib
import sys
import warnings
from collections.abc import Sequence

from quadnav import __version__
from quadnav.cli.commands import COMMANDS, command_in
from quadnav.errors import QuadnavError
from quadnav.signals import report_stop

EXIT_USAGE = 2


class _OneLineErrorParser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors are one line on stderr, exit code 2, naming
    the help of the (sub)command that found them, e.g. ``quadnav tello fly --help`` for a
    misspelt flag of ``tello fly``. A command's positional arguments may come anywhere
    among its flags (``batch MAP1 --seeds 3 MAP2``)."""

    #: Set while :meth:`parse_known_intermixed_args` parses, which calls
    #: :meth:`parse_known_args` for each of its two passes (Python 3.11, 3.12).
    _intermixing = False

    def parse_known_args(self, args=None, namespace=None):  # type: ignore[override]
        """Parse as argparse does, but mixing a command's positionals with its flags, and
        report unrecognised arguments here, under this (sub)command's name."""
        if self._intermixing:
            return super().parse_known_args(args, namespace)
        if self._subparsers is None:  # a command: no subcommands, so nothing to pass down
            self._intermixing = True
            try:
                namespace, extras = self.parse_known_intermixed_args(args, namespace)
            finally:
                self._intermixing = False
        else:
            namespace, extras = super().parse_known_args(args, namespace)
        if extras:
            self.error(f"unrecognized arguments: {' '.join(extras)}")
        return namespace, extras

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The ``quadnav`` argument parser for the command line ``argv``: the command it runs
    is imported and registered with all its flags, every other command only by name and
    help. Without ``argv``, every command is registered in full."""
    parser = _OneLineErrorParser(
        prog="quadnav",
        description="Plan, smooth, fly and show quadrotor flights through 3D maps of boxes.",
    )
    parser.add_argument("--version", action="version", version=f"quadnav {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    chosen = None if argv is None else command_in(argv)
    for name, command in COMMANDS.items():
        if argv is None or name == chosen:
            module = importlib.import_module(f"quadnav.cli.{command.module}")
            getattr(module, command.register)(commands)
        else:
            commands.add_parser(name, help=command.help, aliases=command.aliases)
    return parser


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"quadnav: warning: {message}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code (also used by the console script)."""
    warnings.showwarning = _one_line_warning
    try:  # a stop while the parser is built or reads the flags is a stop too
        argv = sys.argv[1:] if argv is None else list(argv)
        args = build_parser(argv).parse_args(argv)
        return args.handler(args)
    except QuadnavError as error:
        details = getattr(error, "details", None)  # a plug-in's own traceback, once
        if details:
            print(details, file=sys.stderr)
        print(f"quadnav: error: {error}", file=sys.stderr)
        return getattr(error, "exit_code", EXIT_USAGE)
    except (KeyboardInterrupt, Exception) as error:  # a stop in a lazy import, however wrapped
        return report_stop(error)


if __name__ == "__main__":
    sys.exit(main())
