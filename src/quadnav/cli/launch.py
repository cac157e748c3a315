"""The ``quadnav`` console script: stop signals are handled before anything heavy loads.

SIGTERM and SIGHUP are turned into :class:`~quadnav.signals.Stopped` (a
KeyboardInterrupt), so every command handles them exactly as it handles Ctrl-C: it stops
what it is doing, cleans up (a Tello lands, a run folder is left as it was) and exits
with 128 + the signal number (130 for Ctrl-C, 143 for SIGTERM, 129 for SIGHUP). The
command line itself is imported only after the handlers are in place, so an interrupt
during start-up is one line too. A signal that comes while numba loads or compiles a
kernel waits until it is done.
"""

from __future__ import annotations

import _thread
import os
import signal
import sys
from collections.abc import Sequence
from typing import NoReturn

from quadnav.cli.commands import command_in
from quadnav.signals import StopSignalHandler, report_interrupt, report_stop, signal_of

#: The handler of every stop signal. It holds them while numba holds its compiler lock
#: (loading a compiled kernel from its cache, or compiling one): an exception raised half
#: way through that can leave llvmlite's objects half built, and Python's clean-up of them
#: then crashes the process; a stop held so is raised as soon as numba lets go. It holds
#: them for good once the command is done (:func:`console`). Its ``raised`` is the stop
#: last raised: an extension module whose loading that cut short may report an ImportError
#: that has lost it as its cause (numpy's C-level imports do).
_stop_handler = StopSignalHandler()


def install_stop_handlers() -> None:
    """Handle every stop signal with :data:`_stop_handler`."""
    _stop_handler.install()


def watch_kernel_loads() -> None:
    """Tell :data:`_stop_handler` when numba takes and lets go of its compiler lock."""
    from numba.core import event

    class LockWatcher(event.Listener):
        def on_start(self, started: event.Event) -> None:
            _stop_handler.hold()

        def on_end(self, ended: event.Event) -> None:
            _stop_handler.let_go()

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


def main(argv: Sequence[str] | None = None) -> int:
    """Install the stop-signal handlers, then run the command line."""
    install_stop_handlers()
    sys.unraisablehook = stop_again
    os.environ.setdefault("MPLBACKEND", "Agg")  # figures go to files: no display needed
    try:
        if command_in(sys.argv[1:] if argv is None else argv) is not None:
            watch_kernel_loads()  # a command runs: it loads compiled kernels (--help does not)
        from quadnav.cli.main import main as run_command_line
    except (KeyboardInterrupt, Exception) as error:  # a stop in an import, however wrapped
        return report_stop(error, _stop_handler.raised if isinstance(error, ImportError)
                           else None)
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
