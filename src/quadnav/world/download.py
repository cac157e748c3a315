"""Fetching public course maps into the cache (``quadnav maps fetch``), with pooch.

Each file is downloaded from its repository at its pinned commit
(:meth:`~quadnav.world.courses.CourseMap.url`) and kept only if its SHA-256 is the pinned
one. pooch writes a download to a temporary file beside its target and moves it into place
only once the hash matches, removing it otherwise, so a wrong file or a broken connection
leaves nothing in the cache. A member of a zip archive (the RBE595 P2b files) is taken from
the archive downloaded into a temporary folder, checked against the member's own pinned
SHA-256, and written whole or not at all.
"""

from __future__ import annotations

import logging
import tempfile
import zipfile
from pathlib import Path

from quadnav.errors import QuadnavError
from quadnav.files import atomic_output
from quadnav.world.courses import CourseMap, cache_dir, cached_path, sha256


class FetchError(QuadnavError):
    """A course map that could not be fetched: the server could not be reached or refused
    the file, or the file is not the pinned one. Its message is one line naming the map."""


def fetch(entry: CourseMap) -> Path:
    """Download ``entry`` into the cache (see :func:`~quadnav.world.courses.cache_dir`) and
    return its path there; FetchError when that fails, leaving no file behind."""
    import pooch
    from requests.exceptions import RequestException

    pooch.get_logger().setLevel(logging.WARNING)  # no "Downloading ..." lines
    target = cached_path(entry)
    url = entry.url()
    try:
        if entry.member is None:
            pooch.retrieve(url, known_hash=f"sha256:{entry.sha256}", fname=entry.file_name,
                           path=cache_dir(), progressbar=False)
        else:
            _fetch_member(entry, url, target)
    except ValueError:  # pooch's hash mismatch
        raise _mismatch(entry, url) from None
    except RequestException as error:
        raise FetchError(f"{entry.name}: cannot download {url}: {_reason(error)}") from None
    except OSError as error:
        raise QuadnavError(f"{cache_dir()}: cannot write the cache: {error.strerror}"
                           ) from None
    return target


def _fetch_member(entry: CourseMap, url: str, target: Path) -> None:
    """Download the archive of ``entry`` into a temporary folder, check the member's
    SHA-256 and write it to ``target``."""
    import pooch

    assert entry.member is not None
    with tempfile.TemporaryDirectory(prefix="quadnav-fetch-") as folder:
        archive = pooch.retrieve(url, known_hash=None, fname=Path(entry.path).name,
                                 path=folder, progressbar=False)
        try:
            with zipfile.ZipFile(archive) as opened:
                data = opened.read(entry.member)
        except (zipfile.BadZipFile, KeyError):
            raise FetchError(f"{entry.name}: {url} is not a zip archive holding "
                             f"{entry.member}; nothing was kept") from None
    if sha256(data) != entry.sha256:
        raise _mismatch(entry, f"{url} ({entry.member})")
    target.parent.mkdir(parents=True, exist_ok=True)
    with atomic_output(target) as tmp:
        tmp.write_bytes(data)


def _mismatch(entry: CourseMap, where: str) -> FetchError:
    return FetchError(f"{entry.name}: the file from {where} does not have the pinned SHA-256 "
                      f"{entry.sha256[:12]}...; nothing was kept (the origin or the download "
                      "was changed)")


def _reason(error: BaseException) -> str:
    """The root cause of a download error in a few words: ``Connection refused``, ``404
    Client Error: Not Found``, ``[Errno -3] Temporary failure in name resolution`` ..."""
    response = getattr(error, "response", None)
    if response is not None:
        return f"HTTP {response.status_code} {response.reason}"
    seen: set[int] = set()
    cause: BaseException | None = error
    while cause is not None and id(cause) not in seen:
        seen.add(id(cause))
        if isinstance(cause, OSError) and cause.strerror:
            return cause.strerror
        inner = getattr(cause, "reason", None)
        cause = inner if isinstance(inner, BaseException) else (
            cause.__cause__ or cause.__context__ or
            next((a for a in cause.args if isinstance(a, BaseException)), None))
    return str(error).splitlines()[0][:200]

