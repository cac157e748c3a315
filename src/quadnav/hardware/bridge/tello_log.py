"""The flight log: every command, reply and state packet, timestamped, as JSON lines.

Each line of ``tello_log.jsonl`` is one record with ``t`` (seconds since the log was
opened, monotonic clock), ``kind`` and the content:

* ``{"kind": "start", "epoch": UNIX seconds, ...}`` — the first line, with the flight's
  settings;
* ``{"kind": "command", "text": "go 50 0 0 40"}`` — sent to the drone;
* ``{"kind": "reply", "text": "ok"}`` — received from it, as it arrived;
* ``{"kind": "state", "state": {"h": 80, "vgx": 3, ...}}`` — a state packet, as parsed
  by djitellopy;
* ``{"kind": "event", "text": "..."}`` — what the bridge decided (a safe stop, say).

Records are written as they happen (the receiver threads call in too) and flushed; the
file appears at its place when the flight ends, however it ends.
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TextIO

from quadnav.files import atomic_output

#: File name of the log in the output folder.
LOG_NAME = "tello_log.jsonl"


class TelloLog:
    """Writes timestamped records to a text stream; safe to call from several threads."""

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream
        self._lock = threading.Lock()
        self._began = time.monotonic()

    def now(self) -> float:
        """Seconds since the log was opened."""
        return time.monotonic() - self._began

    def write(self, kind: str, **content: object) -> None:
        """Append one record of ``kind`` with ``content`` (JSON-ready values)."""
        with self._lock:
            record = {"t": round(self.now(), 6), "kind": kind, **content}
            self._stream.write(json.dumps(record) + "\n")
            self._stream.flush()

    def command(self, text: str) -> None:
        """A command sent to the drone."""
        self.write("command", text=text)

    def reply(self, text: str) -> None:
        """A reply received from the drone."""
        self.write("reply", text=text)

    def state(self, state: dict) -> None:
        """A state packet received from the drone."""
        self.write("state", state=state)

    def event(self, text: str) -> None:
        """Something the bridge decided or noticed."""
        self.write("event", text=text)


@contextmanager
def open_log(path: str | Path, **settings: object) -> Iterator[TelloLog]:
    """A :class:`TelloLog` writing to ``path``; its first record holds ``settings``.

    The file is written beside ``path`` and moved there when the block ends — also when
    it ends with an error or Ctrl-C, since the log of a failed flight is whole too.
    """
    failure: BaseException | None = None
    with atomic_output(path) as tmp, tmp.open("w", encoding="utf-8") as stream:
        log = TelloLog(stream)
        log.write("start", epoch=time.time(), **settings)
        try:
            yield log
        except BaseException as error:  # kept: a failed flight's log is still written
            failure = error
    if failure is not None:
        raise failure

