"""The stop signals every command handles like Ctrl-C, and the exception they raise.

Ctrl-C (SIGINT) raises KeyboardInterrupt where the program is; SIGTERM and SIGHUP raise
:class:`Stopped`, a KeyboardInterrupt carrying the signal's number, once the console
script (:mod:`quadnav.cli.launch`) has installed its handlers. So one ``except
KeyboardInterrupt`` stops a run cleanly whichever signal came.
"""

from __future__ import annotations

import signal

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
