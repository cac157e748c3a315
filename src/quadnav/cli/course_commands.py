"""``quadnav maps list|fetch``: the public course maps, shipped and fetched."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from quadnav.world.courses import (
    CACHE_ENV,
    START_GOAL,
    CourseMap,
    cache_dir,
    catalogue,
    course_entry,
    status,
)

#: Exit code of ``maps fetch`` when a download failed.
EXIT_FETCH_FAILED = 1
#: How ``maps list`` names each kind of file.
KIND_LABELS = {START_GOAL: "start/goal"}


def list_maps(args: argparse.Namespace) -> int:
    """Print every course map: name, kind, course, status and origin, then the cache."""
    entries = list(catalogue().values())
    statuses = [status(e) for e in entries]  # a fetched file's is its SHA-256, read once
    rows = [("name", "kind", "course", "status", "origin")] + [
        (e.name, KIND_LABELS.get(e.kind, e.kind), e.course, state, e.origin)
        for e, state in zip(entries, statuses, strict=True)]
    widths = [max(len(row[i]) for row in rows) for i in range(4)]
    for row in rows:
        print("  ".join(f"{cell:<{width}}" for cell, width in zip(row, widths, strict=False))
              + "  " + row[4])
    print(f"{statuses.count('shipped')} shipped with quadnav, {statuses.count('fetched')} of "
          f"{len(entries) - statuses.count('shipped')} fetched into the cache {cache_dir()} "
          f"(${CACHE_ENV} moves it)")
    print("Use a map as course:NAME wherever a MAP is accepted, a start/goal file as "
          "--start-goal course:NAME; fetch the others with quadnav maps fetch [NAME...].")
    return 0


def _chosen(names: Sequence[str]) -> list[CourseMap]:
    """The entries ``names`` name (each with or without ``course:``), else every one that is
    not shipped; a one-line error for an unknown name."""
    if not names:
        return [entry for entry in catalogue().values() if entry.shipped is None]
    return [course_entry(name) for name in dict.fromkeys(names)]


def fetch_maps(args: argparse.Namespace) -> int:
    """Fetch the named course maps (all that are not shipped, without names) into the cache;
    exit 1 at the first that fails, saying why."""
    from quadnav.world.download import FetchError, fetch

    for entry in _chosen(args.names):
        state = status(entry)
        if state != "not fetched":
            print(f"{entry.name}: already in the cache" if state == "fetched"
                  else f"{entry.name}: shipped with quadnav, nothing to fetch")
            continue
        try:
            fetch(entry)
        except FetchError as error:
            print(f"quadnav: fetch failed: {error}", file=sys.stderr)
            return EXIT_FETCH_FAILED
        source = "" if entry.member is None else f" from {entry.path.rsplit('/', 1)[-1]}"
        print(f"fetched {entry.name} ({entry.size:,} bytes{source}, SHA-256 checked)")
    print(f"cache: {cache_dir()}")
    return 0


def add_course_commands(commands: argparse._SubParsersAction) -> None:
    """Register ``list`` and ``fetch`` on the subparsers of ``quadnav map``/``maps``."""
    p = commands.add_parser("list", help="the public course maps: shipped, fetched or not",
                            description="List the public course maps quadnav knows: name, "
                                        "kind (map or start/goal file), course, whether it is "
                                        "shipped with quadnav, fetched into the cache or not "
                                        "fetched yet, and its origin (repository@commit/path)"
                                        "; then where the cache is.")
    p.set_defaults(handler=list_maps)

    p = commands.add_parser("fetch", help="download course maps into the cache",
                            description="Download course maps from their public repositories "
                                        "at their pinned commits into the cache, each checked "
                                        "against its pinned SHA-256 (a wrong or failed "
                                        "download keeps nothing). Exit 1 when a download "
                                        f"fails. The cache is ${CACHE_ENV}, else the user's "
                                        "cache folder (see quadnav maps list).")
    p.add_argument("names", nargs="*", metavar="NAME",
                   help="course maps to fetch, e.g. rbe595/map1 (default: every one that is "
                        "not shipped)")
    p.set_defaults(handler=fetch_maps)
