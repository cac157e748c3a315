"""Plug-in points by name: a :class:`Registry` of functions that a user registers in their
own process (:meth:`Registry.register`) or that an installed package declares as entry
points, so the ``quadnav`` command and batch workers know them too::

    [project.entry-points."quadnav.planners"]
    mine = "my_package.my_module:plan_mine"
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from importlib.metadata import entry_points
from typing import Generic, TypeVar

from quadnav.errors import QuadnavError

Plugin = TypeVar("Plugin", bound=Callable)


class Registry(Generic[Plugin]):
    """Functions by name: the built-in ones, then those registered here, then those of
    installed packages' entry points in ``group`` (loaded once, on first use).

    Args:
        kind: what the functions are, for messages ("planner").
        group: the entry-point group ("quadnav.planners").
        builtins: the built-in functions by name, in the order they are listed.
    """

    def __init__(self, kind: str, group: str, builtins: dict[str, Plugin]) -> None:
        self.kind = kind
        self.group = group
        self._plugins = dict(builtins)
        self._loaded = False

    def _all(self) -> dict[str, Plugin]:
        if not self._loaded:
            self._loaded = True
            for point in entry_points(group=self.group):
                self._plugins.setdefault(point.name, point.load())
        return self._plugins

    def register(self, name: str, plugin: Plugin, replace: bool = False) -> None:
        """Make ``plugin`` known as ``name`` in this process. QuadnavError for a name that
        is empty or holds a space or a colon, for something not callable, or for a name
        taken (unless ``replace``)."""
        if not name or any(c.isspace() or c == ":" for c in name):
            raise QuadnavError(f"{self.kind} name {name!r}: expected a word without spaces "
                               "or colons")
        if not callable(plugin):
            raise QuadnavError(f"{self.kind} {name!r}: expected a function, got {plugin!r}")
        if name in self._all() and not replace:
            raise QuadnavError(f"{self.kind} {name!r} is already registered")
        self._plugins[name] = plugin

    def names(self) -> list[str]:
        """Every name known, the built-in ones first."""
        return list(self._all())

    def __contains__(self, name: object) -> bool:
        return name in self._all()

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def get(self, name: str) -> Plugin:
        """The function called ``name``; QuadnavError naming the choices if there is none."""
        if name not in self._all():
            raise QuadnavError(f"unknown {self.kind} {name!r}; expected one of "
                               f"{', '.join(self.names())}")
        return self._plugins[name]
