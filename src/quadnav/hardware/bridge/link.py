"""What the bridge needs from a link to the drone, its errors, and the dry-run link.

A link (:class:`Link`) is djitellopy's ``Tello`` as :class:`~quadnav.hardware.bridge.tello_link.
TelloLink` extends it — or :class:`DryRunLink`, which prints each command instead of
sending it and needs no drone (and no djitellopy).
"""

from __future__ import annotations

import sys
from typing import Protocol, TextIO

from quadnav.hardware.bridge.tello_log import TelloLog

#: Seconds without a state packet, or past a reply's time limit, that count as a lost link.
LINK_TIMEOUT = 1.0
#: The Tello's address on its own Wi-Fi network.
TELLO_IP = "192.168.10.1"


class LinkLostError(Exception):
    """The drone stopped answering: no reply in time, or no state packets."""


class CommandRefusedError(Exception):
    """The drone answered a command with something other than ``ok``."""


class AutoLandingError(Exception):
    """The drone is landing by itself: it answered ``error Auto land``, or its battery
    fell below the level at which a Tello does (:data:`~quadnav.hardware.sdk.LOW_BATTERY`)."""


class Link(Protocol):
    """A connection to one Tello.

    Attributes:
        reports_state: whether state packets come back (False for a dry run).
    """

    reports_state: bool

    def connect(self) -> None:
        """Enter SDK mode (``command``) and wait for the first state packet."""

    def command(self, command: str, timeout: float) -> None:
        """Send ``command`` and wait up to ``timeout`` wall-clock seconds for its ``ok``;
        :class:`LinkLostError`, :class:`AutoLandingError` or :class:`CommandRefusedError`
        otherwise."""

    def send_rc_control(self, left_right_velocity: int, forward_backward_velocity: int,
                        up_down_velocity: int, yaw_velocity: int) -> None:
        """Send the four ``rc`` sticks (no reply)."""

    def state_age(self) -> float:
        """Wall-clock seconds since the last state packet."""

    def get_battery(self) -> int:
        """Battery, percent, from the latest state packet."""

    def get_height(self) -> int:
        """Height above the takeoff floor, cm, from the latest state packet."""

    def settled_height(self) -> int:
        """Height above the takeoff floor, cm, from a state packet sent after the last
        reply (waited for)."""

    def close(self) -> None:
        """Let go of the connection."""


class DryRunLink:
    """Prints every command, one per line, to ``stream`` and logs it; sends nothing."""

    reports_state = False

    def __init__(self, log: TelloLog, stream: TextIO | None = None) -> None:
        self._log = log
        self._stream = stream or sys.stdout  # standard output as it is now

    def _print(self, command: str) -> None:
        self._log.command(command)
        print(command, file=self._stream)

    def connect(self) -> None:
        """Print ``command``."""
        self._print("command")

    def command(self, command: str, timeout: float) -> None:
        """Print ``command``; it counts as done at once."""
        self._print(command)

    def send_rc_control(self, left_right_velocity: int, forward_backward_velocity: int,
                        up_down_velocity: int, yaw_velocity: int) -> None:
        """Print the ``rc`` command."""
        self._print(f"rc {left_right_velocity} {forward_backward_velocity} "
                    f"{up_down_velocity} {yaw_velocity}")

    def state_age(self) -> float:
        """0: a dry run never loses its link."""
        return 0.0

    def get_battery(self) -> int:
        """Not available: a dry run has no drone."""
        raise LinkLostError("a dry run has no battery reading")

    def get_height(self) -> int:
        """Not available: a dry run has no drone."""
        raise LinkLostError("a dry run has no height reading")

    settled_height = get_height

    def close(self) -> None:
        """Nothing to let go of."""
