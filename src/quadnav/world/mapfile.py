"""Reading and writing map files, and resolving a MAP argument to a :class:`World`.

A MAP is a path to a text or JSON map file, the spec of a built-in world such as
``forest:size=50x50x8,density=0.05,seed=3`` (see :mod:`quadnav.world.builtin`), or a public
course map such as ``course:rbe595/map1`` (see :mod:`quadnav.world.courses`).
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from quadnav.errors import MapError, MapWarning
from quadnav.files import atomic_output
from quadnav.inputfiles import special_file
from quadnav.world import builtin, courses
from quadnav.world.jsonmap import format_json_map, parse_json_map
from quadnav.world.model import World
from quadnav.world.reading import decode_text, read_file
from quadnav.world.textmap import format_text_map, parse_text_map


def _is_json(path: Path, text: str) -> bool:
    if path.suffix.lower() == ".json":
        return True
    return path.suffix.lower() != ".txt" and text.lstrip().startswith("{")


#: Warnings about one map shown one by one; the rest are summed up in one line.
SHOWN_WARNINGS = 10


def parse_map(data: bytes, source: str, file_name: str | None = None) -> World:
    """A World named ``source`` from the bytes of a map file in either format: JSON if the
    file's name (``file_name``, default ``source``) ends in ``.json``, text if it ends in
    ``.txt``, else JSON if it starts with ``{``. Its first :data:`SHOWN_WARNINGS` repairs
    are warned one by one, the rest in one line."""
    text = decode_text(data, source)
    with _summed_up_warnings(source):
        if _is_json(Path(file_name or source), text):
            return parse_json_map(text, source)
        return parse_text_map(text, source)


@contextmanager
def _summed_up_warnings(source: str) -> Iterator[None]:
    """Hold the :class:`MapWarning` s raised in the block; when it ends, warn the first
    :data:`SHOWN_WARNINGS` of them and, if there were more, one line counting the rest (a
    map with a million swapped blocks printed a million lines). Other warnings pass."""
    shown: list[Warning | str] = []
    count = 0
    passed_on = warnings.showwarning

    def hold(message: Warning | str, category: type[Warning], *args: object,
             **kwargs: object) -> None:
        nonlocal count
        if not issubclass(category, MapWarning):
            passed_on(message, category, *args, **kwargs)
            return
        count += 1
        if count <= SHOWN_WARNINGS:
            shown.append(message)

    with warnings.catch_warnings():
        warnings.simplefilter("always", MapWarning)
        warnings.showwarning = hold
        yield
    for message in shown:
        warnings.warn(str(message), MapWarning, stacklevel=3)
    if count > SHOWN_WARNINGS:
        warnings.warn(f"{source}: {count - SHOWN_WARNINGS:,} more warnings like these",
                      MapWarning, stacklevel=3)


def read_map(path: str | Path) -> World:
    """A World from a text or JSON map file; MapError naming the file and line if bad."""
    return parse_map(read_file(path), str(path))


def load_world(source: str | Path | World) -> World:
    """A World from a map file path, a built-in world spec, a ``course:NAME`` course map
    (offline: shipped, or fetched before), or a World (returned as is)."""
    if isinstance(source, World):
        return source
    try:
        is_file = Path(source).is_file()
    except OSError:  # e.g. a name too long to be a file: maybe a built-in world spec
        is_file = False
    if is_file or special_file(source):
        return read_map(source)
    if courses.is_course_name(source):
        data, entry = courses.read_course_file(str(source), courses.MAP)
        return parse_map(data, str(source), entry.file_name)
    if builtin.is_builtin_spec(str(source)):
        return builtin.build_world(str(source))
    raise MapError(str(source), "no such map file, and not a built-in world "
                   f"(built-in: {', '.join(builtin.world_names())}) or a course map "
                   "(course:NAME: quadnav maps list)")


def format_map(world: World, path: str | Path) -> str:
    """The world in the format that ``path``'s extension names: .json or .txt."""
    suffix = Path(path).suffix.lower()
    if suffix == ".json":
        return format_json_map(world)
    if suffix == ".txt":
        return format_text_map(world)
    raise MapError(str(path), "expected a file name ending in .json (JSON map) or .txt (text map)")


def write_map(world: World, path: str | Path) -> None:
    """Write the world as a map file: JSON for a ``.json`` path, text for ``.txt``."""
    text = format_map(world, path)
    with atomic_output(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
