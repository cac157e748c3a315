"""Bringing a Tello down: ``stop``, ``land``, and knowing when it is on the floor.

:class:`Lander` sends ``stop`` (hover) and ``land`` over a link and says in words how it
went. A landing counts as confirmed by the ``ok`` of ``land`` or by fresh state packets
with the drone on the floor (a height of at most :data:`LANDED_HEIGHT_CM`); ``land`` is
resent up to :data:`LAND_ATTEMPTS` times while neither comes. After ``error Auto land``
(the drone lands by itself) it waits for the state packets instead.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from quadnav.hardware.bridge.dead_reckoning import DeadReckoning, Estimate
from quadnav.hardware.bridge.frames import GROUND_Z
from quadnav.hardware.bridge.link import AutoLandingError, CommandRefusedError, Link, LinkLostError
from quadnav.hardware.bridge.tello_log import TelloLog

#: Drone seconds a landing and a ``stop`` may take before the reply is due.
LAND_TIME = 10.0
STOP_TIME = 2.0
#: How many times ``land`` is sent.
LAND_ATTEMPTS = 3
#: A reported height at or below this counts as on the floor, cm.
LANDED_HEIGHT_CM = 5
#: Wall-clock seconds between looks at the state while waiting for the drone to land.
_POLL = 0.01


@dataclass(frozen=True)
class Landing:
    """How a landing went: ``confirmed`` (by ``ok`` or the state packets), in words, and
    where the dead reckoning puts the drone on the floor (``place``; None unconfirmed)."""

    confirmed: bool
    text: str
    place: Estimate | None = None


@dataclass(frozen=True)
class Lander:
    """Stops and lands the drone on ``link``.

    Attributes:
        link: the link to the drone.
        estimator: where the drone is (told of each ``land`` as a move straight down),
            for the messages and the landing place.
        log: gets an event for each refused or unanswered command.
        timeout: wall-clock seconds to wait for the reply to a command that takes the
            given drone seconds.
        link_timeout: wall-clock seconds after which a state packet is stale.
    """

    link: Link
    estimator: DeadReckoning
    log: TelloLog
    timeout: Callable[[float], float]
    link_timeout: float

    def stop(self) -> str:
        """Send ``stop``; how it went, in words."""
        try:
            self.link.command("stop", self.timeout(STOP_TIME))
        except LinkLostError:
            return "'stop' got no reply"
        except (AutoLandingError, CommandRefusedError) as error:
            self.log.event(f"stop: {error}")
            return str(error)
        return "'stop' answered ok (hovering)"

    def land(self) -> Landing:
        """Send ``land`` until the landing is confirmed (see the module's description)."""
        for _ in range(LAND_ATTEMPTS):
            try:
                self.estimator.begin_move(np.zeros(3))  # straight down
                self.link.command("land", self.timeout(LAND_TIME))
                self.estimator.end_move()
                place = self.floor_place()
                return Landing(True, f"landed at about {place.text}", place)
            except AutoLandingError as error:
                self.log.event(f"land: {error}")
                if self._await_floor():
                    return self._on_floor()
            except (LinkLostError, CommandRefusedError) as error:
                self.log.event(f"land: {error}")
            if self.on_floor():  # already down (a refused 'land' comes after the landing)
                return self._on_floor()
        return Landing(False, f"'land' got no answer ({LAND_ATTEMPTS} tries)")

    def _on_floor(self) -> Landing:
        """Landed, as the state packets show: one message whichever way it was seen."""
        place = self.floor_place()
        return Landing(True, f"it is on the floor at about {place.text} (state packets)",
                       place)

    def _await_floor(self) -> bool:
        """Wait (up to a landing's time) for fresh state packets with the drone on the
        floor; False if they stop or it does not come down."""
        deadline = time.monotonic() + self.timeout(LAND_TIME)
        while time.monotonic() < deadline:
            if self.link.state_age() > self.link_timeout:
                return False
            if self.on_floor():
                return True
            time.sleep(_POLL)
        return False

    def on_floor(self) -> bool:
        """Whether fresh state packets say the drone is on the floor."""
        link = self.link
        return (link.reports_state and link.state_age() <= self.link_timeout
                and link.get_height() <= LANDED_HEIGHT_CM)

    def floor_place(self) -> Estimate:
        """The floor under the dead-reckoned position, with its uncertainty."""
        estimate = self.estimator.estimate()
        x, y, _ = estimate.point
        return Estimate(np.array([x, y, GROUND_Z]), estimate.sigma)
