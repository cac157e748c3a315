"""World stage: map files, exact box geometry, built-in worlds.

* :class:`World` — boundary, blocks (N, 6), colours, optional start, goal and margin.
* :func:`load_world` — a map file (text or JSON) or a built-in world spec.
* :func:`read_map`, :func:`write_map`, :func:`read_start_goal` — file formats.
"""

from quadnav.world.mapfile import load_world, parse_map, read_map, write_map
from quadnav.world.model import Hit, World
from quadnav.world.startgoal import read_start_goal

__all__ = ["Hit", "World", "load_world", "parse_map", "read_map", "read_start_goal", "write_map"]
