"""3D figures of a :class:`~quadnav.world.World` with matplotlib.

Blocks are drawn as solid boxes in their own colours, the boundary as a transparent
box with dark edges, the start as a red sphere and the goal as a green one. Axes are
labelled in metres and scaled equally, so a cube looks like a cube; only a side shorter
than a fifth of the longest (a long thin map) is drawn longer, and the legend says by
how much.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.legend import Legend
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from mpl_toolkits.mplot3d import Axes3D
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from quadnav.viz.figures import new_figure
from quadnav.viz.layout import finish
from quadnav.viz.style import GOAL_COLOR, START_COLOR
from quadnav.world.model import World

#: Shortest drawn side of the map's box, relative to its longest.
MIN_SIDE = 0.2

# Corner indices of the six faces of a box whose corners are numbered by bits (x, y, z).
_FACES = np.array([[0, 1, 3, 2], [4, 5, 7, 6], [0, 1, 5, 4],
                   [2, 3, 7, 6], [0, 2, 6, 4], [1, 3, 7, 5]])
_CORNER_BITS = np.array([[(i >> 0) & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)])


def box_faces(boxes: np.ndarray) -> np.ndarray:
    """Face polygons (6 N, 4, 3) of boxes (N, 6), for a Poly3DCollection."""
    lower, upper = boxes[:, None, :3], boxes[:, None, 3:]
    corners = lower + _CORNER_BITS[None] * (upper - lower)  # (N, 8, 3)
    return corners[:, _FACES].reshape(-1, 4, 3)


def box_aspect(extent: np.ndarray) -> np.ndarray:
    """The drawn lengths (3,) of a box with sides ``extent`` (3,), m: the sides
    themselves, each at least :data:`MIN_SIDE` of the longest."""
    extent = np.asarray(extent, dtype=float)
    return np.maximum(extent, MIN_SIDE * float(np.max(extent)))


def stretch_note(extent: np.ndarray) -> str | None:
    """What :func:`box_aspect` stretched for a box with sides ``extent`` (3,), m, e.g.
    ``"not to scale: y stretched 3.8x, z stretched 3.8x"``; None when it is drawn to
    scale."""
    stretch = box_aspect(extent) / np.asarray(extent, dtype=float)
    stretched = {name: factor for name, factor in zip("xyz", stretch, strict=True)
                 if factor > 1.0 + 1e-9}
    if not stretched:
        return None
    return "not to scale: " + ", ".join(f"{name} stretched {factor:.2g}x"
                                        for name, factor in stretched.items())


def _sphere(ax: Axes3D, center: np.ndarray, radius: float, color: str) -> None:
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 24), np.linspace(0, np.pi, 12))
    ax.plot_surface(center[0] + radius * np.cos(u) * np.sin(v),
                    center[1] + radius * np.sin(u) * np.sin(v),
                    center[2] + radius * np.cos(v), color=color, linewidth=0, shade=True,
                    zorder=10)


def draw_world(ax: Axes3D, world: World, start: np.ndarray | None = None,
               goal: np.ndarray | None = None) -> list:
    """Draw blocks, boundary, start and goal on a 3D axes; returns legend handles.

    Start and goal are drawn over the blocks, so they stay visible behind walls.
    """
    ax.computed_zorder = False
    handles: list = []
    if len(world.blocks):
        colors = np.repeat(world.colors, 6, axis=0)
        ax.add_collection3d(Poly3DCollection(box_faces(world.blocks), facecolors=colors,
                                             edgecolors=(0, 0, 0, 0.25), linewidths=0.3,
                                             alpha=0.9))
        handles.append(Patch(facecolor=tuple(world.colors[0]), label=f"blocks ({len(world)})"))
    ax.add_collection3d(Poly3DCollection(box_faces(world.boundary[None]),
                                         facecolors=(0.5, 0.5, 0.5, 0.06),
                                         edgecolors=(0, 0, 0, 0.6), linewidths=0.8))
    handles.append(Patch(facecolor=(0.5, 0.5, 0.5, 0.2), edgecolor="black", label="boundary"))
    radius = 0.02 * float(np.max(world.extent))
    for point, color, label in ((start, START_COLOR, "start"), (goal, GOAL_COLOR, "goal")):
        if point is not None:
            _sphere(ax, np.asarray(point, dtype=float), radius, color)
            handles.append(Line2D([], [], marker="o", color=color, linestyle="", label=label))
    lower, upper = world.lower, world.upper
    ax.set_xlim(lower[0], upper[0])
    ax.set_ylim(lower[1], upper[1])
    ax.set_zlim(lower[2], upper[2])
    ax.set_box_aspect(tuple(box_aspect(world.extent)))
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    return handles


def map_legend(fig: Figure, world: World, handles: list, **options) -> Legend:
    """The legend of a figure of ``world``, outside its axes: ``handles`` and, when the
    3D box is not to scale, :func:`stretch_note` as a last entry without a symbol.
    ``options`` go to :meth:`~matplotlib.figure.Figure.legend` (default: beside the
    axes, top right, 8 points)."""
    note = stretch_note(world.extent)
    if note is not None:
        handles = [*handles, Line2D([], [], linestyle="", label=note)]
    return fig.legend(handles=handles, **{"loc": "outside right upper", "fontsize": 8,
                                          **options})


def world_figure(world: World, start: np.ndarray | None = None,
                 goal: np.ndarray | None = None, title: str | None = None) -> Figure:
    """A figure of the world seen obliquely, with the legend beside it and the world's
    name as title."""
    fig = new_figure((9, 7))
    ax = fig.add_subplot(projection="3d")
    handles = draw_world(ax, world, start, goal)
    ax.view_init(elev=30, azim=-60)
    map_legend(fig, world, handles)
    ax.set_title(title or world.name, fontsize=9)
    return finish(fig)
