"""The ``quadnav`` console script: stop signals are handled before anything heavy loads.

SIGTERM and SIGHUP are turned into :class:`Stopped` (a KeyboardInterrupt), so every
command handles them exactly as it handles Ctrl-C: it stops what it is doing, cleans up
(a Tello lands, a run folder is left as it was) and exits with 128 + the signal number
(130 for Ctrl-C, 143 for SIGTERM, 129 for SIGHUP). The command line itself is imported
only after the handlers are in place, so an interrupt during start-up is one line too. A
signal that comes while numba loads or compiles a kernel waits until it is done.
"""

from __future__ import annotations

import _thread
import os
import signal
import sys
from collections.abc import Sequence
from types import FrameType
from typing import NoReturn

from quadnav.cli.commands import command_in
from quadnav.signals import STOP_SIGNALS, Stopped, interrupt_behind, interrupt_for, signal_of


class _StopHandler:
    """The handler of every stop signal: it raises the signal's exception (see
    :func:`~quadnav.signals.interrupt_for`) where the program is, unless it is holding
    stops (:attr:`holding` above 0). It holds them while numba holds its compiler lock
    (loading a compiled kernel from its cache, or compiling one): an exception raised half
    way through that can leave llvmlite's objects half built, and Python's clean-up of
    them then crashes the process. A stop held so is raised as soon as numba lets go
    (:meth:`on_lock`). It also holds them for good once the command is done
    (:func:`console`)."""

    def __init__(self) -> None:
        self.holding = 0  # one for each reason; numba's lock is re-entrant
        self.held: int | None = None
        #: The stop last raised: an extension module whose loading it cut short may report
        #: an ImportError that has lost it as its cause (numpy's C-level imports do).
        self.raised: KeyboardInterrupt | None = None

    def __call__(self, signum: int, frame: FrameType | None) -> None:
        if self.holding:
            self.held = self.held or signum
        else:
            self._raise(signum)

    def on_lock(self, taken: bool) -> None:
        """numba took (``taken``) or let go of its compiler lock."""
        self.holding += 1 if taken else -1
        if not self.holding and self.held is not None:
            signum, self.held = self.held, None
            self._raise(signum)

    def _raise(self, signum: int) -> NoReturn:
        self.raised = interrupt_for(signum)
        raise self.raised


_stop_handler = _StopHandler()


def install_stop_handlers() -> None:
    """Handle every stop signal with :data:`_stop_handler`."""
    for signum in STOP_SIGNALS:
        signal.signal(signum, _stop_handler)


def watch_kernel_loads() -> None:
    """Tell :data:`_stop_handler` when numba takes and lets go of its compiler lock."""
    from numba.core import event

    class LockWatcher(event.Listener):
        def on_start(self, started: event.Event) -> None:
            _stop_handler.on_lock(True)

        def on_end(self, ended: event.Event) -> None:
            _stop_handler.on_lock(False)

    event.register("numba:compiler_lock", LockWatcher())


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


def report_stop(error: KeyboardInterrupt | ImportError,
                raised: KeyboardInterrupt | None = None) -> int:
    """Say on one line that the run was stopped, and return the exit code, when ``error``
    is a Ctrl-C or stop signal or an import it interrupted (its cause, or ``raised``: the
    stop the handlers raised during the import, which some extension modules' ImportError
    no longer names); otherwise raise it again."""
    interrupt = interrupt_behind(error) or raised
    if interrupt is None:
        raise error
    return report_interrupt(interrupt)


def report_interrupt(interrupt: KeyboardInterrupt) -> int:
    """Say on one line that the run was stopped; returns the exit code."""
    what = (f"stopped by {signal.Signals(interrupt.signum).name}"
            if isinstance(interrupt, Stopped) else "interrupted")
    print(f"quadnav: {what}", file=sys.stderr)
    return interrupted_exit_code(interrupt)


def main(argv: Sequence[str] | None = None) -> int:
    """Install the stop-signal handlers, then run the command line."""
    install_stop_handlers()
    sys.unraisablehook = stop_again
    os.environ.setdefault("MPLBACKEND", "Agg")  # figures go to files: no display needed
    try:
        if command_in(sys.argv[1:] if argv is None else argv) is not None:
            watch_kernel_loads()  # a command runs: it loads compiled kernels (--help does not)
        from quadnav.cli.main import main as run_command_line
    except (KeyboardInterrupt, ImportError) as error:
        return report_stop(error, _stop_handler.raised)
    return run_command_line(argv)


def console() -> NoReturn:
    """The console script: :func:`main`, then exit at once with its code.

    Everything the command writes is closed by then; the output streams are flushed, and
    the interpreter's own clean-up (a third of a second of finalizers for the compiled
    kernels and plotting) is skipped, with stop signals held from the moment the
    command returns, so that none arrives half way. Output piped into a reader that
    stops early (``quadnav worlds | head``) ends the command as SIGPIPE would, exit 141,
    without a traceback."""
    # Each increment comes before any call, where Python could raise a stop.
    try:
        code = main()
        _stop_handler.holding += 1
    except KeyboardInterrupt as interrupt:
        _stop_handler.holding += 1
        code = report_interrupt(interrupt)
    except BrokenPipeError:  # the reader of the output went away (``| head``): as SIGPIPE
        _stop_handler.holding += 1
        os._exit(128 + signal.SIGPIPE)
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        os._exit(128 + signal.SIGPIPE)
    sys.stderr.flush()
    os._exit(code)


if __name__ == "__main__":
    console()
