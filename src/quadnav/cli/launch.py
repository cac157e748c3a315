"""The ``quadnav`` console script: stop signals are handled before anything heavy loads.

SIGTERM and SIGHUP are turned into :class:`Stopped` (a KeyboardInterrupt), so every
command handles them exactly as it handles Ctrl-C: it stops what it is doing, cleans up
(a Tello lands, a run folder is left as it was) and exits with 128 + the signal number
(130 for Ctrl-C, 143 for SIGTERM, 129 for SIGHUP). The command line itself is imported
only after the handlers are in place, so an interrupt during start-up is one line too.
"""

from __future__ import annotations

import signal
import sys
from collections.abc import Sequence
from types import FrameType

#: Signals handled like Ctrl-C.
STOP_SIGNALS = (signal.SIGTERM, signal.SIGHUP)


class Stopped(KeyboardInterrupt):
    """A stop signal other than Ctrl-C, raised where the program was; ``signum`` says
    which."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def _raise_stopped(signum: int, frame: FrameType | None) -> None:
    raise Stopped(signum)


def interrupted_exit_code(interrupt: KeyboardInterrupt) -> int:
    """The shell's exit code for a run ended by ``interrupt``: 128 + the signal number."""
    return 128 + getattr(interrupt, "signum", signal.SIGINT)


def report_interrupt(interrupt: KeyboardInterrupt) -> int:
    """Say on one line that the run was stopped; returns the exit code."""
    what = (f"stopped by {signal.Signals(interrupt.signum).name}"
            if isinstance(interrupt, Stopped) else "interrupted")
    print(f"quadnav: {what}", file=sys.stderr)
    return interrupted_exit_code(interrupt)


def main(argv: Sequence[str] | None = None) -> int:
    """Install the stop-signal handlers, then run the command line."""
    for signum in STOP_SIGNALS:
        signal.signal(signum, _raise_stopped)
    try:
        from quadnav.cli.main import main as run_command_line
    except KeyboardInterrupt as interrupt:
        return report_interrupt(interrupt)
    return run_command_line(argv)


if __name__ == "__main__":
    sys.exit(main())
