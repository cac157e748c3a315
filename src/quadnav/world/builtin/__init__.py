"""Built-in worlds, generated from a spec such as ``forest:size=50x50x8,density=0.05,seed=3``.

A spec is a world name, optionally followed by ``:`` and ``key=value`` pairs joined by
commas; left-out keys take their defaults. Building is deterministic: the same spec gives
the same world. Every built world

* is named by its canonical spec, which lists every parameter (``world.name``), so
  ``build_world(world.name)`` rebuilds it;
* has ``margin`` :data:`DEFAULT_MARGIN` and a start and goal that are free in the world
  inflated by that margin;
* is proven connected there (:func:`quadnav.world.connectivity.connected`). A layout
  that fails the check is drawn again from a random generator seeded with
  ``(seed, attempt)``, up to :data:`MAX_ATTEMPTS` times, before giving up with a
  :class:`~quadnav.errors.MapError`.
"""

from __future__ import annotations

import numpy as np

from quadnav.errors import MapError
from quadnav.plugins import Registry
from quadnav.specs import (
    ParamInfo,
    SpecError,
    SpecInfo,
    canonical_spec,
    describe_params,
)
from quadnav.world.builtin import empty, forest, maze, window
from quadnav.world.builtin.base import Generator, Layout
from quadnav.world.connectivity import connected, default_resolution
from quadnav.world.model import DEFAULT_MARGIN, World

__all__ = [
    "DEFAULT_MARGIN",
    "DEFAULT_WORLD_SPEC",
    "WORLDS",
    "ParamInfo",
    "SpecInfo",
    "build_world",
    "describe_worlds",
    "is_builtin_spec",
    "world_names",
]

#: The world flown or shown when no MAP is given.
DEFAULT_WORLD_SPEC = "forest"
#: Layouts drawn for one spec before giving up on finding a connected one.
MAX_ATTEMPTS = 20

#: The built-in worlds by name: ours, those of installed packages' ``quadnav.worlds``
#: entry points, those registered (``WORLDS.register(name, generator)``).
WORLDS: Registry[Generator] = Registry("world", "quadnav.worlds", {
    g.name: g for g in (empty.GENERATOR, forest.GENERATOR, window.GENERATOR, maze.GENERATOR)
}, expects=Generator)


def world_names() -> list[str]:
    """Names of the built-in worlds."""
    return WORLDS.names()


def describe_worlds() -> list[SpecInfo]:
    """Every built-in world with a summary and its parameters."""
    generators = {name: WORLDS.get(name) for name in WORLDS}
    return [SpecInfo(name, g.summary, describe_params(g.params))
            for name, g in generators.items()]


def is_builtin_spec(text: str) -> bool:
    """Whether ``text`` names a built-in world (the part before any ``:``).

    The parameters are not checked; a path such as ``forest.txt`` is not a spec.
    """
    return text.partition(":")[0].strip() in WORLDS


def build_world(spec: str) -> World:
    """The world that ``spec`` describes; MapError with a one-line reason if it is bad.

    Raises MapError for an unknown world or parameter, a repeated parameter, a value of
    the wrong type or out of range, values the generator cannot build (e.g. a density
    too high to place the trunks), or no connected layout in :data:`MAX_ATTEMPTS` draws.
    """
    name, colon, rest = (part.strip() for part in spec.partition(":"))
    if name not in WORLDS:
        raise MapError(spec, f"unknown built-in world {name!r} "
                       f"(known: {', '.join(WORLDS)})")
    generator = WORLDS.get(name)
    try:
        canonical, values = canonical_spec(name, generator.params, rest if colon else None)
        seed = values.get("seed", 0)
        for attempt in range(MAX_ATTEMPTS):
            layout = generator.layout(values, np.random.default_rng([seed, attempt]))
            world = _world(layout, canonical)
            if _flyable(world):
                return world
    except SpecError as error:
        raise MapError(spec, str(error)) from None
    narrow = 2 * default_resolution(layout.size) + 2 * DEFAULT_MARGIN
    raise MapError(spec, f"no layout in {MAX_ATTEMPTS} attempts had start and goal provably "
                   f"connected (at this map size, passages narrower than about {narrow:.2g} m "
                   "may be missed); try fewer obstacles or a smaller map")


def _world(layout: Layout, name: str) -> World:
    """The World of a generated layout."""
    return World(
        boundary=np.concatenate([np.zeros(3), layout.size]),
        blocks=layout.blocks,
        colors=layout.colors,
        start=layout.start,
        goal=layout.goal,
        margin=DEFAULT_MARGIN,
        name=name,
    )


def _flyable(world: World) -> bool:
    """Whether start and goal are free and provably connected at :data:`DEFAULT_MARGIN`
    (:func:`connected` answers False for a point that is not free)."""
    inflated = world.inflate(DEFAULT_MARGIN)
    return connected(inflated, world.start, world.goal)
