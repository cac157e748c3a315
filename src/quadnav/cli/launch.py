"""The ``quadnav`` console script: stop signals are handled before anything heavy loads.

SIGTERM and SIGHUP are turned into :class:`Stopped` (a KeyboardInterrupt), so every
command handles them exactly as it handles Ctrl-C: it stops what it is doing, cleans up
(a Tello lands, a run folder is left as it was) and exits with 128 + the signal number
(130 for Ctrl-C, 143 for SIGTERM, 129 for SIGHUP). The command line itself is imported
only after the handlers are in place, so an interrupt during start-up is one line too.
"""

from __future__ import annotations

import _thread
import os
import signal
import sys
from collections.abc import Sequence
from types import FrameType
from typing import NoReturn

from quadnav.signals import STOP_SIGNALS, Stopped, signal_of


def _raise_stopped(signum: int, frame: FrameType | None) -> None:
    raise Stopped(signum)


def stop_again(unraisable: sys.UnraisableHookArgs) -> None:
    """``sys.unraisablehook``: a Ctrl-C or stop signal whose exception was raised inside a
    finalizer (a ``__del__`` that the garbage collector ran, where Python only prints an
    exception and carries on) is raised again, so that it still stops the run; any other
    unraisable exception is printed as usual. The signal is sent again from a new thread,
    which runs once the main thread lets go (at the latest after Python's 5 ms switch
    interval), by when the finalizer is done: sent from here, it would be raised in here."""
    if isinstance(unraisable.exc_value, KeyboardInterrupt):
        _thread.start_new_thread(_thread.interrupt_main, (signal_of(unraisable.exc_value),))
    else:
        sys.__unraisablehook__(unraisable)


def interrupted_exit_code(interrupt: KeyboardInterrupt) -> int:
    """The shell's exit code for a run ended by ``interrupt``: 128 + the signal number."""
    return 128 + signal_of(interrupt)


def report_interrupt(interrupt: KeyboardInterrupt) -> int:
    """Say on one line that the run was stopped; returns the exit code."""
    what = (f"stopped by {signal.Signals(interrupt.signum).name}"
            if isinstance(interrupt, Stopped) else "interrupted")
    print(f"quadnav: {what}", file=sys.stderr)
    return interrupted_exit_code(interrupt)


def main(argv: Sequence[str] | None = None) -> int:
    """Install the stop-signal handlers, then run the command line."""
    for signum in STOP_SIGNALS:
        if signum != signal.SIGINT:  # Ctrl-C raises KeyboardInterrupt already
            signal.signal(signum, _raise_stopped)
    sys.unraisablehook = stop_again
    try:
        from quadnav.cli.main import main as run_command_line
    except KeyboardInterrupt as interrupt:
        return report_interrupt(interrupt)
    return run_command_line(argv)


def console() -> NoReturn:
    """The console script: :func:`main`, then exit at once with its code.

    Everything the command writes is closed by then; the output streams are flushed, and
    the interpreter's own clean-up (a third of a second of finalizers for the compiled
    kernels and plotting) is skipped, with stop signals blocked so that none arrives
    half way."""
    code = main()
    signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


if __name__ == "__main__":
    console()
