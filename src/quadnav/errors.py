"""Error types that carry a message meant for the user.

Every error a user can cause (a bad map file, a bad built-in world spec, a start
inside a block) derives from :class:`QuadnavError`; the CLI prints its message on
one line and exits with code 2.
"""

from __future__ import annotations

import errno

#: Errors of a write that found no room: no space, over quota, file too large.
DISK_FULL = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG})


class QuadnavError(Exception):
    """An error caused by the user's input; its message is one line for the user."""


class MapError(QuadnavError):
    """A map file or built-in world spec that cannot be read.

    The message names the source (a file path or a spec) and, where there is one,
    the 1-based line number, then says what was expected.
    """

    def __init__(self, source: str, message: str, line: int | None = None) -> None:
        self.source = str(source)
        self.line = line
        self.reason = message
        where = self.source if line is None else f"{self.source}:{line}"
        super().__init__(f"{where}: {message}")


class WriteError(QuadnavError):
    """A file that could not be written: ``path`` and why (the system's words, e.g. "No
    space left on device"), with ``full`` when there was no room for it."""

    def __init__(self, path: object, reason: str, full: bool = False) -> None:
        self.path = path
        self.reason = reason
        self.full = full
        super().__init__(f"{path}: cannot write: {reason}")

    @classmethod
    def of(cls, path: object, error: OSError) -> WriteError:
        """The error of a write of ``path`` that failed with ``error``."""
        return cls(path, error.strerror or str(error), error.errno in DISK_FULL)


class MapWarning(UserWarning):
    """Something in a map was repaired while reading it (a block clipped or dropped)."""


class PlanningWarning(UserWarning):
    """A planning query was adjusted (e.g. a start inside the safety margin)."""


class ControlWarning(UserWarning):
    """A controller flown at settings it barely suits (e.g. a slow control rate)."""
