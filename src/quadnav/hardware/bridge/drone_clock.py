"""Drone time for the bridge: the wall clock times a time scale, or a dry run's clock.

A real drone's seconds are the wall clock's (``time_scale`` 1); an emulator run
``time_scale`` times faster counts that many drone seconds per wall-clock second.
"""

from __future__ import annotations

import time


class Clock:
    """Drone time: seconds since the clock was made, times ``time_scale``."""

    def __init__(self, time_scale: float = 1.0) -> None:
        self.time_scale = time_scale
        self._began = time.monotonic()

    def now(self) -> float:
        """Drone seconds since the start."""
        return self.time_scale * (time.monotonic() - self._began)

    def sleep_until(self, when: float) -> None:
        """Wait until drone time ``when``."""
        delay = (when - self.now()) / self.time_scale
        if delay > 0:
            time.sleep(delay)

    def wall(self, seconds: float) -> float:
        """Drone ``seconds`` in wall-clock seconds."""
        return seconds / self.time_scale


class VirtualClock(Clock):
    """A dry run's clock: waiting moves it on at once."""

    def __init__(self) -> None:
        super().__init__()
        self._now = 0.0

    def now(self) -> float:
        """Drone seconds waited so far."""
        return self._now

    def sleep_until(self, when: float) -> None:
        """Jump to ``when``."""
        self._now = max(self._now, when)
