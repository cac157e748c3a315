"""Where a mission comes from, for messages: :class:`Source` names the file, and the line of
a key in it (tomllib gives no line numbers: they are found in the file's text), or the flag
that set the key on top of it."""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

from pydantic import BaseModel

from quadnav.errors import QuadnavError


class Source:
    """Where a mission comes from, for messages: its name and, for a file, its text."""

    def __init__(self, name: str, text: str | None = None,
                 given: Mapping[str, str] | None = None) -> None:
        self.name = name
        self.text = text
        self.given = dict(given or {})

    def where(self, path: list[str]) -> str:
        """``FILE:LINE: dotted.key``, the line where the key ``path`` (or the nearest
        table that holds it) is set (without a line when none is found); for a key set
        on top of the file (:meth:`MissionConfig.with_changes`), the name it was given."""
        dotted = ".".join(path)
        if dotted in self.given:
            return self.given[dotted]
        line = key_line(self.text or "", path)
        place = self.name if line is None else f"{self.name}:{line}"
        return f"{place}: {'.'.join(path)}"

    def refusal(self, error: Mapping[str, Any], root: type[BaseModel]) -> QuadnavError:
        """An error of a validation against the schema ``root`` as one line."""
        path = [str(part) for part in error["loc"] if not isinstance(part, int)]
        kind = error["type"]
        if kind == "extra_forbidden":
            known = section_at(root, path[:-1]).model_fields
            message = f"unknown key; expected one of {', '.join(known)}"
        elif kind in ("model_type", "model_attributes_type", "dict_type"):
            message = f"expected a table [{'.'.join(path)}], got {error['input']!r}"
        else:
            message = error["msg"]
        return QuadnavError(f"{self.where(path)}: {message}")


def section_at(root: type[BaseModel], path: list[str]) -> type[BaseModel]:
    """The schema of the table at ``path`` of the schema ``root`` (its key names)."""
    model = root
    for key in path:
        field = model.model_fields.get(key)
        annotation = getattr(field, "annotation", None)
        if not (isinstance(annotation, type) and issubclass(annotation, BaseModel)):
            break
        model = annotation
    return model


HEADER = re.compile(r"^\s*\[\s*([^\]\[]+?)\s*\]\s*(#.*)?$")
KEY = re.compile(r"^\s*([A-Za-z0-9_.\"' -]+?)\s*=")


def key_line(text: str, path: list[str]) -> int | None:
    """The 1-based line of ``text`` (TOML) that sets the key ``path``, else that of the
    deepest table of it that is set; None when neither is found."""
    best: tuple[int, int] | None = None  # (depth matched, line)
    table: list[str] = []
    for number, line in enumerate(text.splitlines(), start=1):
        header = HEADER.match(line)
        if header:
            table = [part.strip().strip("\"'") for part in header.group(1).split(".")]
            found = table
        else:
            key = KEY.match(line)
            if key is None:
                continue
            found = table + [part.strip().strip("\"'") for part in key.group(1).split(".")]
            inline = re.findall(r"[{,]\s*([A-Za-z0-9_]+)\s*=", line[key.end():])
            if len(found) < len(path) and path[len(found)] in inline:
                found = [*found, path[len(found)]]
        depth = len(found) if found == path[:len(found)] else 0
        if depth and (best is None or depth > best[0]):
            best = (depth, number)
    return None if best is None else best[1]
