"""The map seen from above on a plain 2D axes, and figures that show a run both ways.

A top view is drawn in 2D, to scale, with x and y ticks of its own: blocks as
rectangles in their colours (the higher ones over the lower ones), the boundary
outlined, start and goal as markers. :func:`plot_points` and :func:`draw_map` draw on
either kind of axes, so one function can fill an oblique 3D view and a top view alike.
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import PatchCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Rectangle
from mpl_toolkits.mplot3d import Axes3D

from quadnav.viz.figures import new_figure
from quadnav.viz.lines import draw_polylines
from quadnav.viz.map3d import draw_world
from quadnav.viz.style import GOAL_COLOR, START_COLOR
from quadnav.world.model import World

#: Elevation and azimuth of the oblique view, degrees.
OBLIQUE = (30.0, -60.0)
#: Margin around the boundary in a top view, relative to its larger side.
PAD = 0.02
#: A top view this many times wider than deep goes under the oblique view, not beside.
WIDE = 2.0
#: Inches of a top view's height beyond the map's own, for its title and x labels.
TOP_MARGIN = 1.0
#: Colour of a geofence's outline.
FENCE_COLOR = "#444444"


def plot_points(ax: Axes, points: np.ndarray, **style) -> list[Line2D]:
    """Plot the polyline through ``points`` (N, 3), m: in 3D on a 3D axes, its x and y
    on a 2D one (a view from above). ``style`` goes to :meth:`~matplotlib.axes.Axes.plot`."""
    points = np.asarray(points, dtype=float)
    return ax.plot(*points.T[:3 if isinstance(ax, Axes3D) else 2], **style)


def draw_world_top(ax: Axes, world: World, start: np.ndarray | None = None,
                   goal: np.ndarray | None = None) -> list:
    """Draw the map from above on a 2D axes, to scale, in metres; returns legend handles
    for the entries :func:`~quadnav.viz.map3d.draw_world` has (blocks, boundary, start,
    goal)."""
    order = np.argsort(world.blocks[:, 5], kind="stable")  # the highest drawn last
    handles: list = []
    if len(world.blocks):
        rects = [Rectangle(block[:2], *(block[3:5] - block[:2])) for block in world.blocks[order]]
        ax.add_collection(PatchCollection(rects, facecolors=world.colors[order],
                                          edgecolors=(0, 0, 0, 0.4), linewidths=0.5,
                                          alpha=0.9, zorder=2))
        handles.append(Patch(facecolor=tuple(world.colors[0]), label=f"blocks ({len(world)})"))
    ax.add_patch(Rectangle(world.lower[:2], *world.extent[:2], facecolor=(0.5, 0.5, 0.5, 0.1),
                           edgecolor="black", linewidth=0.8, zorder=1))
    handles.append(Patch(facecolor=(0.5, 0.5, 0.5, 0.2), edgecolor="black", label="boundary"))
    for point, color, label in ((start, START_COLOR, "start"), (goal, GOAL_COLOR, "goal")):
        if point is not None:
            handles += ax.plot(*np.asarray(point, dtype=float)[:2], marker="o", color=color,
                               markeredgecolor="black", markersize=9, linestyle="",
                               zorder=30, label=label)
    pad = PAD * float(np.max(world.extent[:2]))
    ax.set_xlim(world.lower[0] - pad, world.upper[0] + pad)
    ax.set_ylim(world.lower[1] - pad, world.upper[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    return handles


def draw_fence_top(ax: Axes, world: World, margin: float) -> Line2D:
    """The geofence of ``world`` at ``margin`` m seen from above, dashed: the boundary
    shrunk and every block grown by the margin (their outlines); returns the line."""
    fence = world.inflate(margin)
    boxes = np.vstack([fence.boundary, fence.blocks])
    corners = np.stack([boxes[:, [0, 1]], boxes[:, [3, 1]], boxes[:, [3, 4]], boxes[:, [0, 4]],
                        boxes[:, [0, 1]]], axis=1)
    return draw_polylines(ax, np.concatenate([corners, np.zeros((*corners.shape[:2], 1))],
                                             axis=2),
                          color=FENCE_COLOR, linestyle=":", linewidth=0.9, zorder=3,
                          label=f"geofence ({margin:g} m in)")


def draw_map(ax: Axes, world: World, start: np.ndarray | None = None,
             goal: np.ndarray | None = None) -> list:
    """:func:`~quadnav.viz.map3d.draw_world` on a 3D axes, :func:`draw_world_top` on a
    2D one; returns the legend handles."""
    draw = draw_world if isinstance(ax, Axes3D) else draw_world_top
    return draw(ax, world, start, goal)


def two_views(world: World, size: tuple[float, float]) -> tuple[Figure, Axes3D, Axes]:
    """A figure (constrained layout) with an oblique 3D axes titled "oblique view" and a
    2D axes titled "top view": side by side in ``size`` inches or, for a :data:`WIDE`
    map, the top view below, as high as it needs to be to scale, and the figure as much
    higher as that takes."""
    width, depth = world.extent[:2]
    if width > WIDE * depth:
        top_height = size[0] * depth / width + TOP_MARGIN
        fig = new_figure((size[0], size[1] + top_height))
        grid = fig.add_gridspec(2, 1, height_ratios=(size[1], top_height))
    else:
        fig = new_figure(size)
        grid = fig.add_gridspec(1, 2)
    oblique = fig.add_subplot(grid[0], projection="3d")
    oblique.view_init(*OBLIQUE)
    top = fig.add_subplot(grid[1])
    for ax, title in ((oblique, "oblique view"), (top, "top view")):
        ax.set_title(title, fontsize=10)
    return fig, oblique, top
