"""The stop signals every command handles like Ctrl-C, the exception they raise, and
the one handler that raises or holds them.

Ctrl-C (SIGINT) raises KeyboardInterrupt where the program is; SIGTERM and SIGHUP raise
:class:`Stopped`, a KeyboardInterrupt carrying the signal's number, once the console
script (:mod:`quadnav.cli.launch`) has installed its handlers. So one ``except
KeyboardInterrupt`` stops a run cleanly whichever signal came. Every place that handles
stop signals does so with a :class:`StopSignalHandler`: the console script (which holds
them while numba compiles), a run folder's move (:mod:`quadnav.runfolder`, which holds
them while the files move in) and a Tello flight (:mod:`quadnav.hardware.bridge.flight`, which
holds them while the drone lands).
"""

from __future__ import annotations

import signal
import sys
import threading
from types import CodeType, FrameType, TracebackType
from typing import NoReturn

#: The signals that stop a run the way Ctrl-C does.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


class Stopped(KeyboardInterrupt):
    """A stop signal other than Ctrl-C, raised where the program was; ``signum`` says
    which."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def interrupt_for(signum: int) -> KeyboardInterrupt:
    """The exception the stop signal ``signum`` raises: KeyboardInterrupt for Ctrl-C,
    :class:`Stopped` for the others."""
    return KeyboardInterrupt() if signum == signal.SIGINT else Stopped(signum)


def interrupt_behind(error: BaseException) -> KeyboardInterrupt | None:
    """The Ctrl-C or stop signal that ``error`` is, or that caused it: an extension
    module whose loading is interrupted reports an ``ImportError`` caused by it."""
    seen: BaseException | None = error
    while seen is not None and not isinstance(seen, KeyboardInterrupt):
        seen = seen.__cause__ or seen.__context__
    return seen


def signal_of(interrupt: KeyboardInterrupt) -> int:
    """The signal number behind ``interrupt`` (SIGINT for a plain KeyboardInterrupt)."""
    return int(getattr(interrupt, "signum", signal.SIGINT))


def signal_name(signum: int) -> str:
    """How a message names the stop signal ``signum``: ``Ctrl-C (SIGINT)``, ``SIGTERM``..."""
    name = signal.Signals(signum).name
    return f"Ctrl-C ({name})" if signum == signal.SIGINT else name


def interrupted_exit_code(interrupt: KeyboardInterrupt) -> int:
    """The shell's exit code for a run ended by ``interrupt``: 128 + the signal number."""
    return 128 + signal_of(interrupt)


def report_interrupt(interrupt: KeyboardInterrupt) -> int:
    """Say on one line that the run was stopped; returns the exit code."""
    what = (f"stopped by {signal.Signals(interrupt.signum).name}"
            if isinstance(interrupt, Stopped) else "interrupted")
    print(f"quadnav: {what}", file=sys.stderr)
    return interrupted_exit_code(interrupt)


def report_stop(error: BaseException, raised: KeyboardInterrupt | None = None) -> int:
    """Say on one line that the run was stopped, and return the exit code, when ``error``
    is a Ctrl-C or stop signal or what it became in the code it cut short (its cause or
    context: an import's ImportError, the RuntimeError of a class whose ``__set_name__``
    it interrupted), or comes with ``raised``: the stop the handlers raised during an
    import, which some extension modules' ImportError no longer names; otherwise raise
    ``error`` again."""
    interrupt = interrupt_behind(error) or raised
    if interrupt is None:
        raise error
    return report_interrupt(interrupt)


class StopSignalHandler:
    """The handler of every stop signal: it acts on a signal at once, or holds it back.

    A signal is held while :attr:`holding` is above 0 (a count of reasons to hold; True
    and False will do), or when it is handled as the function whose code is ``guard``
    begins (its very first instruction); it is then noted in :attr:`held`. Otherwise it
    is acted on: it raises its exception (:func:`interrupt_for`) where the program is,
    noted in :attr:`raised`; with ``pass_on``, it goes instead to the handler that
    :meth:`install` replaced. With ``hold_after_first``, the first signal raised holds
    every later one (a stop that is being handled must not be cut short by the next).
    Change ``holding`` with a plain assignment or ``+=``: Python runs signal handlers
    only as a function begins, after a call and at a loop's turn, so no signal slips in
    between.

    :meth:`install` makes it the handler of every stop signal and :meth:`restore` puts
    back those it replaced; ``with`` does both. Handlers can be set in the main thread
    only: in another, nothing is installed and nothing held.

    Attributes:
        holding: how many reasons there are to hold signals back.
        held: the signals held and not yet acted on or taken, in order of arrival.
        raised: the exception the handler raised last, if any.
    """

    def __init__(self, holding: int = 0, *, guard: CodeType | None = None,
                 pass_on: bool = False, hold_after_first: bool = False) -> None:
        self.holding = holding
        self.held: list[int] = []
        self.raised: KeyboardInterrupt | None = None
        self._guard = guard
        self._pass_on = pass_on
        self._hold_after_first = hold_after_first
        self._previous: dict[int, object] = {}

    def install(self) -> None:
        """Handle every stop signal, keeping the handlers replaced. With ``pass_on``, a
        signal ignored (or handled outside Python) is left so."""
        if threading.current_thread() is not threading.main_thread():
            return
        try:
            for signum in STOP_SIGNALS:
                if self._pass_on and signal.getsignal(signum) in (signal.SIG_IGN, None):
                    continue
                self._previous[signum] = signal.signal(signum, self.handle)
        except BaseException:  # a stop before all were set: put those set back
            self.restore()
            raise

    def restore(self) -> None:
        """Put back the handlers :meth:`install` replaced. With ``pass_on``, the first
        signal still held then goes to them (the rest are dropped)."""
        for signum, previous in self._previous.items():
            signal.signal(signum, signal.SIG_DFL if previous is None else previous)
        self._previous = {}
        if self._pass_on and self.held:
            signal.raise_signal(self.held[0])

    def __enter__(self) -> StopSignalHandler:
        self.install()
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 traceback: TracebackType | None) -> None:
        self.restore()

    def handle(self, signum: int, frame: FrameType | None) -> None:
        """The signal handler: hold ``signum`` or act on it."""
        if self.holding or (frame is not None and frame.f_code is self._guard):
            self.held.append(signum)
            return
        if self._hold_after_first:  # before any call, where the next could be handled
            self.holding += 1
        self._act(signum, frame)

    def hold(self) -> None:
        """From now on, hold every signal (until :meth:`let_go`)."""
        self.holding += 1

    def let_go(self) -> None:
        """One reason fewer to hold; once none is left, the signals held so far are
        acted on in order (the first that raises drops the rest)."""
        self.holding -= 1
        if not self.holding:
            for signum in self.take():
                self._act(signum, None)

    def take(self) -> list[int]:
        """The signals held so far, which are then no longer held."""
        taken, self.held = self.held, []
        return taken

    def _act(self, signum: int, frame: FrameType | None) -> None:
        if self._pass_on:
            self._hand_on(signum, frame)
        else:
            self._raise(signum)

    def _hand_on(self, signum: int, frame: FrameType | None) -> None:
        previous = self._previous[signum]
        if callable(previous):
            previous(signum, frame)
        else:  # SIG_DFL: the default action, e.g. SIGTERM ends the process
            signal.signal(signum, previous)
            signal.raise_signal(signum)

    def _raise(self, signum: int) -> NoReturn:
        self.raised = interrupt_for(signum)
        raise self.raised
