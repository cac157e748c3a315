"""What an input path is: a file is read only when it is a regular file, since reading a FIFO
or a device waits for a writer, or for ever, and a folder is no file."""

from __future__ import annotations

import os
import stat
from pathlib import Path

#: What a path that exists but is no regular file is, by its ``stat`` type.
_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISSOCK, "a socket"),
          (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"))


def special_file(path: str | Path) -> str | None:
    """What ``path`` is if it exists and is not a regular file (``"a FIFO"``, ``"a folder"``,
    ...), else None (a regular file, nothing there, or no name a file could have)."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return None
    if stat.S_ISREG(mode):
        return None
    return next((kind for is_kind, kind in _KINDS if is_kind(mode)), "a special file")


def not_a_file(kind: str, expected: str) -> str:
    """What is wrong with an input that is ``kind`` (see :func:`special_file`), for a
    message that names the path before it."""
    return f"{kind}, not a regular file: expected {expected}"
