"""The public course maps, named ``course:NAME`` (e.g. ``course:rbe595/map1``).

The catalogue (``coursemaps/catalogue.json``, package data) pins each map to its public
repository, full commit, path (for a file inside a zip, the archive and the member), SHA-256
and size. rotorpy's MIT-licensed worlds are shipped in ``coursemaps/rotorpy`` with rotorpy's
licence; the others are fetched into the user's cache by :mod:`quadnav.world.download`
(``quadnav maps fetch``). Everything here is offline: reading a course map never touches the
network, and a map that is not in the cache is a one-line error naming the fetch command.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
from dataclasses import dataclass
from importlib import resources
from pathlib import Path, PurePosixPath
from urllib.parse import quote

from quadnav.errors import MapError
from quadnav.world.reading import read_file

#: What a map argument starts with to name a course map.
PREFIX = "course:"
#: Environment variable naming the cache folder of fetched maps.
CACHE_ENV = "QUADNAV_CACHE_DIR"
#: Environment variable replacing :data:`DEFAULT_URL` as the base of every download.
URL_ENV = "QUADNAV_MAPS_URL"
#: Base of the download URLs: ``{base}/{repo}/{commit}/{path}`` serves a file of a public
#: GitHub repository at a commit.
DEFAULT_URL = "https://raw.githubusercontent.com"
#: The two kinds of file in the catalogue: a map, or an RBE595 start/goal file.
MAP, START_GOAL = "map", "start_goal"
#: How a message names each kind, and where a file of that kind goes.
_KIND_TEXT = {MAP: "a map", START_GOAL: "a start/goal file"}
_KIND_USE = {MAP: "pass it as the map", START_GOAL: "pass it with --start-goal"}

_DATA = resources.files("quadnav.world") / "coursemaps"


@dataclass(frozen=True)
class CourseMap:
    """One public course file and where it comes from.

    Attributes:
        name: the name after ``course:``, e.g. ``rbe595/map1``.
        kind: :data:`MAP` or :data:`START_GOAL`.
        course: the course or project it comes from, e.g. ``RBE595 P2a train``.
        repo: its GitHub repository, ``owner/name``.
        commit: the full commit it is pinned to.
        path: its path in the repository (for a zip member: the archive's path).
        sha256: SHA-256 of the file's bytes (for a zip member: of the member's bytes).
        size: its size, bytes.
        member: for a file inside a zip archive, its path in the archive; else None.
        archive_sha256: for a zip member, the pinned archive's SHA-256 (provenance only: a
            fetch checks the member's own SHA-256); else None.
        archive_size: for a zip member, the archive's size, bytes; else None.
        shipped: the file's path under ``coursemaps/`` when quadnav ships it; else None.
    """

    name: str
    kind: str
    course: str
    repo: str
    commit: str
    path: str
    sha256: str
    size: int
    member: str | None = None
    archive_sha256: str | None = None
    archive_size: int | None = None
    shipped: str | None = None

    @property
    def file_name(self) -> str:
        """Its file name in the cache: the name with the file's extension, e.g.
        ``rbe595/map1.txt``."""
        return self.name + PurePosixPath(self.member or self.path).suffix

    @property
    def origin(self) -> str:
        """``repo@short commit/path`` (``...zip:member`` for a member of an archive)."""
        where = self.path if self.member is None else f"{self.path}:{self.member}"
        return f"{self.repo}@{self.commit[:7]}/{where}"

    def url(self, base: str | None = None) -> str:
        """The URL of the file (of the archive, for a member) under ``base`` (default:
        :func:`download_base`)."""
        base = (base or download_base()).rstrip("/")
        return f"{base}/{self.repo}/{self.commit}/{quote(self.path)}"


@functools.cache
def catalogue() -> dict[str, CourseMap]:
    """Every course file by name, in the catalogue's (alphabetical) order."""
    entries = json.loads((_DATA / "catalogue.json").read_text(encoding="utf-8"))
    return {entry["name"]: CourseMap(**entry) for entry in entries}


def cache_dir() -> Path:
    """The folder fetched maps are kept in: ``$QUADNAV_CACHE_DIR``, else the user's cache
    folder for quadnav (the folder ``pooch.os_cache("quadnav")`` names, e.g.
    ``~/.cache/quadnav`` on Linux)."""
    folder = os.environ.get(CACHE_ENV)
    if folder:
        return Path(folder).expanduser()
    import platformdirs

    return Path(platformdirs.user_cache_dir("quadnav"))


def download_base() -> str:
    """The base URL of downloads: ``$QUADNAV_MAPS_URL``, else :data:`DEFAULT_URL`."""
    return os.environ.get(URL_ENV) or DEFAULT_URL


def cached_path(entry: CourseMap) -> Path:
    """Where ``entry`` is (or would be) in the cache."""
    return cache_dir() / entry.file_name


def is_course_name(text: str | Path) -> bool:
    """Whether a map or start/goal argument names a course file (starts with ``course:``)."""
    return isinstance(text, str) and text.startswith(PREFIX)


def course_entry(text: str, kind: str | None = None) -> CourseMap:
    """The catalogue entry that ``text`` names (``course:rbe595/map1`` or ``rbe595/map1``).

    MapError for an unknown name (listing the known ones) or, when ``kind`` is given, for a
    file of the other kind.
    """
    name = text.removeprefix(PREFIX)
    entry = catalogue().get(name)
    if entry is None:
        raise MapError(text, "no such course map; known: " + ", ".join(catalogue())
                       + " (quadnav maps list)")
    if kind is not None and entry.kind != kind:
        raise MapError(text, f"{_KIND_TEXT[entry.kind]}, not {_KIND_TEXT[kind]}: "
                       f"{_KIND_USE[entry.kind]}")
    return entry


def fetch_command(entry: CourseMap) -> str:
    """The command that fetches ``entry``."""
    return f"quadnav maps fetch {entry.name}"


def is_available(entry: CourseMap) -> bool:
    """Whether ``entry`` can be read offline: shipped, or in the cache with its pinned
    SHA-256."""
    if entry.shipped is not None:
        return True
    path = cached_path(entry)
    return path.is_file() and sha256(path.read_bytes()) == entry.sha256


def status(entry: CourseMap) -> str:
    """``shipped``, ``fetched`` (in the cache, as pinned) or ``not fetched``."""
    if entry.shipped is not None:
        return "shipped"
    return "fetched" if is_available(entry) else "not fetched"


def read_course_file(text: str, kind: str) -> tuple[bytes, CourseMap]:
    """The bytes of the course file of ``kind`` that ``text`` names, and its entry.

    A shipped file is read from the package; a fetched one from the cache, checked against
    its pinned SHA-256. MapError, naming the fetch command to run, when it is not in the
    cache or no longer matches.
    """
    entry = course_entry(text, kind)
    if entry.shipped is not None:
        return (_DATA / entry.shipped).read_bytes(), entry
    path = cached_path(entry)
    if not path.is_file():
        raise MapError(text, f"not fetched yet: run {fetch_command(entry)} first (it "
                       f"downloads the file from {entry.repo} on GitHub)")
    data = read_file(path)
    if sha256(data) != entry.sha256:
        raise MapError(text, f"the cached file {path} does not match its pinned SHA-256: "
                       f"run {fetch_command(entry)} to fetch it again")
    return data, entry


def sha256(data: bytes) -> str:
    """The SHA-256 of ``data``, hex."""
    return hashlib.sha256(data).hexdigest()
