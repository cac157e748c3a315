"""The link to a Tello: the djitellopy client, every packet logged, a watchdog on replies.

djitellopy (2.5) keeps one UDP socket per process for commands and replies (bound to port
8889) and one receiver thread for state packets (port 8890); each drone's replies and
latest state live in its module-level ``drones[host]`` record. :class:`TelloLink` is a
``djitellopy.Tello`` whose record logs every reply and state packet as it arrives (with
its time), and whose commands are logged as they are sent. Its :meth:`TelloLink.command`
waits for the reply under a watchdog: no state packet for ``link_timeout`` seconds, or no
reply within the command's own time limit, raises :class:`LinkLostError` at once instead of
djitellopy's fixed 7 s (or 20 s) wait and silent retries — a retried ``go`` could fly
twice. Replies still queued when a command is sent (late ones, whose command gave up) are
dropped, logged; one later still cannot be told from the new command's (the SDK numbers
nothing), which is why the bridge takes any overdue reply for a lost link and lands.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from djitellopy import Tello
from djitellopy import tello as djitellopy_module

from quadnav.hardware.bridge.link import (
    LINK_TIMEOUT,
    AutoLandingError,
    CommandRefusedError,
    LinkLostError,
)
from quadnav.hardware.bridge.tello_log import TelloLog
from quadnav.hardware.sdk import AUTO_LAND, MOTION_STOPPED

#: Wall-clock seconds the drone has to answer ``command`` and to send its first state.
CONNECT_TIMEOUT = 3.0
#: How often the waits look for news, s.
_POLL = 0.005


class _Replies(list):
    """djitellopy's reply queue for one drone, logging each reply as it arrives."""

    def __init__(self, log: TelloLog) -> None:
        super().__init__()
        self._log = log

    def append(self, data: bytes) -> None:
        self._log.reply(data.decode("utf-8", errors="replace").rstrip("\r\n"))
        super().append(data)


class _Record(dict):
    """djitellopy's per-drone record (``responses``, ``state``), logging state packets,
    passing them to ``on_state``, counting them and noting when the last one came (monotonic
    seconds, None before the first)."""

    def __init__(self, log: TelloLog, on_state: Callable[[dict], None]) -> None:
        super().__init__(responses=_Replies(log), state={})
        self._log = log
        self._on_state = on_state
        self.last_state: float | None = None
        self.states = 0

    def __setitem__(self, key: str, value: object) -> None:
        super().__setitem__(key, value)
        if key == "state" and value:
            self.last_state = time.monotonic()
            self.states += 1
            self._log.state(value)
            self._on_state(value)


class TelloLink(Tello):
    """A djitellopy client for the drone at ``host`` that logs to ``log``, hands each
    state packet to ``on_state`` (on the receiver thread) and raises
    :class:`LinkLostError` after ``link_timeout`` seconds of silence."""

    def __init__(self, host: str, log: TelloLog, on_state: Callable[[dict], None],
                 link_timeout: float = LINK_TIMEOUT) -> None:
        super().__init__(host=host, retry_count=1)
        self.log = log
        self.link_timeout = link_timeout
        self._record = _Record(log, on_state)
        djitellopy_module.drones[host] = self._record

    reports_state = True

    def connect(self, wait_for_state: bool = True) -> None:
        """Enter SDK mode and wait for the first state packet (as djitellopy does, within
        :data:`CONNECT_TIMEOUT`); LinkLostError if either does not come."""
        try:
            self.command("command", CONNECT_TIMEOUT)
        except LinkLostError as error:
            raise LinkLostError(f"no connection to the Tello at {self.address[0]}: {error}"
                                ) from None
        if wait_for_state:
            self._await_state(0, CONNECT_TIMEOUT, f"no state packet from the Tello at "
                              f"{self.address[0]} within {CONNECT_TIMEOUT:g} s of 'command'")

    def _await_state(self, seen: int, timeout: float, problem: str) -> None:
        """Wait until more than ``seen`` state packets have come; LinkLostError saying
        ``problem`` when none more comes within ``timeout`` s."""
        began = time.monotonic()
        while self._record.states <= seen:
            if time.monotonic() - began > timeout:
                raise LinkLostError(problem)
            time.sleep(_POLL)

    def send_command_with_return(self, command: str,
                                 timeout: float = Tello.RESPONSE_TIMEOUT) -> str:
        """Send ``command`` and return its reply, under the watchdog (see the module)."""
        self._record["responses"].clear()
        self.send_command_without_return(command)
        return self._next_reply(command, time.monotonic(), timeout)

    def _next_reply(self, command: str, sent: float, timeout: float) -> str:
        """The next reply, waited for under the watchdog: ``command`` was sent at
        monotonic time ``sent`` and is due ``timeout`` s later."""
        replies = self._record["responses"]
        while not replies:
            now = time.monotonic()
            last = self._record.last_state
            if last is not None and now - max(last, sent) > self.link_timeout:
                raise LinkLostError(f"no state packet for {self.link_timeout:g} s while waiting "
                                    f"for the reply to '{command}'")
            if now - sent > timeout:
                raise LinkLostError(f"no reply to '{command}' within {timeout:.2f} s")
            time.sleep(_POLL)
        self.last_received_command_timestamp = time.time()
        return replies.pop(0).decode("utf-8", errors="replace").rstrip("\r\n")

    def send_command_without_return(self, command: str) -> None:
        """Send ``command`` (logged) and return at once; LinkLostError if it cannot be
        sent."""
        self.log.command(command)
        try:
            djitellopy_module.client_socket.sendto(command.encode("utf-8"), self.address)
        except OSError as error:  # e.g. no route: not on the Tello's Wi-Fi
            raise LinkLostError(f"cannot send '{command}' to {self.address[0]}: "
                                f"{error.strerror}") from None

    def command(self, command: str, timeout: float) -> None:
        """Send a control command and wait up to ``timeout`` s for its ``ok``.

        A ``stop`` that ends a motion gets two replies: the motion's ``error Stopped``,
        then its own; the first is passed over.

        Raises:
            LinkLostError: no reply in time, or the state packets stopped.
            AutoLandingError: the reply ``error Auto land``: the drone lands by itself.
            CommandRefusedError: any other reply.
        """
        sent = time.monotonic()
        reply = self.send_command_with_return(command, timeout).strip()
        if command == "stop" and reply == MOTION_STOPPED:
            reply = self._next_reply(command, sent, timeout).strip()
        if reply.lower() == "ok":
            return
        if reply == AUTO_LAND:
            raise AutoLandingError(f"the Tello answered '{command}' with '{reply}': it is "
                                   "landing by itself")
        raise CommandRefusedError(f"the Tello answered '{command}' with '{reply}'")

    def settled_height(self) -> int:
        """Height above the takeoff floor, cm, from the first state packet to arrive from
        now (the latest may have left the drone before the last reply did: at ten a second,
        during a takeoff's climb); LinkLostError if none comes for ``link_timeout`` s."""
        self._await_state(self._record.states, self.link_timeout,
                          f"no state packet for {self.link_timeout:g} s while waiting for "
                          "the height after the takeoff")
        return self.get_height()

    def state_age(self) -> float:
        """Seconds since the last state packet (inf before the first)."""
        last = self._record.last_state
        return float("inf") if last is None else time.monotonic() - last

    def close(self) -> None:
        """Forget this drone in djitellopy's records (the bridge lands it itself)."""
        self.is_flying = False
        self.end()

