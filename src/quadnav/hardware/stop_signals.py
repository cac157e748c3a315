"""Stop signals during a flight: the first one stops it, later ones cannot cut the landing short.

While a :class:`StopSignals` block runs (in the main thread), the first SIGINT, SIGTERM or
SIGHUP raises where the program is, as it would anyway: KeyboardInterrupt for Ctrl-C,
:class:`~quadnav.signals.Stopped` (a KeyboardInterrupt carrying ``signum``) for the
others, so the bridge stops the drone and lands it. From then on — and from
:meth:`StopSignals.hold` on, which the bridge calls before it lands — every further stop
signal is only noted in :attr:`StopSignals.held`: a second Ctrl-C, or a service manager's
SIGTERM after SIGHUP, must not abort the landing. The handlers that were in place come
back when the block ends (SIGKILL, which cannot be caught, still ends the program).
"""

from __future__ import annotations

import signal
import threading
from types import FrameType, TracebackType

from quadnav.signals import STOP_SIGNALS, interrupt_for


def signal_name(signum: int) -> str:
    """How a message names the stop signal ``signum``: ``Ctrl-C (SIGINT)``, ``SIGTERM``..."""
    name = signal.Signals(signum).name
    return f"Ctrl-C ({name})" if signum == signal.SIGINT else name


class StopSignals:
    """Stop-signal handling for one flight (see the module's description).

    Attributes:
        held: the signals noted while holding and not yet taken (:meth:`take`), in
            order of arrival.
    """

    def __init__(self) -> None:
        self.held: list[int] = []
        self._holding = False
        self._previous: dict[int, object] = {}

    def __enter__(self) -> StopSignals:
        if threading.current_thread() is threading.main_thread():
            self._previous = {signum: signal.signal(signum, self._handle)
                              for signum in STOP_SIGNALS}
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 traceback: TracebackType | None) -> None:
        for signum, handler in self._previous.items():
            signal.signal(signum, signal.SIG_DFL if handler is None else handler)
        self._previous = {}

    def hold(self) -> None:
        """From now on, note stop signals instead of raising."""
        self._holding = True

    def take(self) -> list[int]:
        """The signals held so far that were not taken yet."""
        taken, self.held = self.held, []
        return taken

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        if self._holding:
            self.held.append(signum)
            return
        self._holding = True
        raise interrupt_for(signum)
