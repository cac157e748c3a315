"""Writing output files whole or not at all."""

from __future__ import annotations

import csv
import io
import os
import tempfile
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

from quadnav.errors import WriteError


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextmanager
def atomic_output(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success move it to ``path``.

    The file at ``path`` is therefore either the complete new file or untouched, and
    the temporary file is removed on failure. The new file gets the usual permissions
    (0666 less the umask). An unwritable place is a one-line :class:`~quadnav.errors.WriteError`.
    """
    path = Path(path)
    try:
        fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    except OSError as error:
        raise WriteError.of(path, error) from None
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        tmp.chmod(0o666 & ~_umask())
        os.replace(tmp, path)
    except OSError as error:
        raise WriteError.of(path, error) from None
    finally:
        tmp.unlink(missing_ok=True)


def csv_text(header: Sequence[str] | None, rows: Iterable[Iterable[object]]) -> str:
    """The rows as CSV text (the csv module's quoting, ``\n`` line ends), after the line
    ``header`` if given."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    if header is not None:
        writer.writerow(header)
    writer.writerows(rows)
    return out.getvalue()


def numbers_csv(header: Sequence[str], rows: Iterable[Iterable[float]]) -> str:
    """Rows of numbers (e.g. an (N, K) array) as CSV text under ``header``, every number
    at full precision (the shortest text that reads back as exactly it)."""
    return csv_text(header, ([repr(float(v)) for v in row] for row in rows))
