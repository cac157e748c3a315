"""Figures of differential-drive plans: the tree as integrated arcs, the centre path and
the wheel tracks, the control profiles, and biased against unbiased sampling.

Tree edges are drawn as the arcs the robot would drive (not as straight lines between
states), lightly; the centre path in red, outlined; the left and right wheel tracks thin
beside it. Legends stand outside the plots.
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import PatchCollection
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Rectangle
from numpy.typing import ArrayLike

from quadnav.kinodynamic.diffdrive import (
    DiffDrive,
    arc_samples,
    control_profile,
    wheel_tracks,
)
from quadnav.kinodynamic.result import KinoResult
from quadnav.kinodynamic.world2d import World2D
from quadnav.viz.figures import new_figure
from quadnav.viz.layout import finish
from quadnav.viz.lines import draw_polylines
from quadnav.viz.style import GOAL_COLOR, PATH_COLOR, START_COLOR, TREE_COLOR, outlined
from quadnav.viz.topview import WIDE

#: Tree edges drawn at most; a larger tree is thinned to an evenly spread subset.
MAX_TREE_EDGES = 20_000
#: Chords each tree edge is drawn with.
TREE_EDGE_CHORDS = 8
LEFT_COLOR = "tab:purple"
RIGHT_COLOR = "tab:orange"
RECT_COLOR = (0.6, 0.6, 0.6)
#: Largest drawing of a map, inches (width, height), and the room around each drawing
#: for its tick labels, axis labels and title (width, height).
MAP_AREA = (9.0, 7.5)
MAP_MARGIN = (0.9, 1.3)
#: Room for a legend beside a map (width) or below maps (height), inches.
LEGEND_ROOM = 2.2
#: Least height of a map figure, inches.
MIN_HEIGHT = 4.0


def draw_world2d(ax: Axes, world: World2D) -> None:
    """Rectangles filled grey and the boundary outlined, axes in metres, equal scale."""
    rects = [Rectangle(r[:2], *(r[2:] - r[:2])) for r in world.rects]
    ax.add_collection(PatchCollection(rects, facecolor=RECT_COLOR, edgecolor=(0, 0, 0, 0.4),
                                      linewidth=0.4))
    ax.add_patch(Rectangle(world.lower, *world.extent, fill=False, edgecolor="black",
                           linewidth=1.0))
    pad = 0.02 * float(np.max(world.extent))
    ax.set_xlim(world.lower[0] - pad, world.upper[0] + pad)
    ax.set_ylim(world.lower[1] - pad, world.upper[1] + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")


def map_figure_size(world: World2D, grid: tuple[int, int], legend: tuple[float, float],
                    min_width: float) -> tuple[float, float]:
    """Size, inches, of a figure with ``grid`` (rows, columns) plots of ``world``, each
    drawn to scale as large as :data:`MAP_AREA` lets it be, with ``legend`` inches
    (width, height) more for the legend, and at least ``min_width`` wide (for the
    titles) and :data:`MIN_HEIGHT` high."""
    extent = np.asarray(world.extent, dtype=float)
    drawn = extent * min(MAP_AREA[0] / extent[0], MAP_AREA[1] / extent[1])
    rows, columns = grid
    return (max(columns * (drawn[0] + MAP_MARGIN[0]) + legend[0], min_width),
            max(rows * (drawn[1] + MAP_MARGIN[1]) + legend[1], MIN_HEIGHT))


def draw_diffdrive(ax: Axes, world: World2D, result: KinoResult, model: DiffDrive,
                   goal: ArrayLike | None = None, goal_radius: float | None = None) -> None:
    """The world, the tree as integrated arcs, the centre path and wheel tracks, the
    start (with its heading) and the goal region, each labelled for a legend."""
    draw_world2d(ax, world)
    count = len(result.tree_states) - 1
    if count:
        shown = 1 + np.linspace(0, count - 1, min(count, MAX_TREE_EDGES)).astype(int)
        parents = result.tree_states[result.tree_parents[shown]]
        arcs = arc_samples(parents, result.tree_controls[shown], result.tree_durations[shown],
                           TREE_EDGE_CHORDS)
        draw_polylines(ax, arcs, color=TREE_COLOR, linewidth=0.4,
                       label=f"tree ({count:,} edges)")
    if result.solved:
        centre, left, right, _ = wheel_tracks(result, model, 1e-3 * float(np.max(world.extent)))
        ax.plot(*left.T, color=LEFT_COLOR, linewidth=0.7, label="left wheel")
        ax.plot(*right.T, color=RIGHT_COLOR, linewidth=0.7, label="right wheel")
        ax.plot(*centre.T, color=PATH_COLOR, linewidth=1.6, path_effects=outlined(1.6),
                label=f"centre ({result.duration:.1f} s)")
    start = result.tree_states[0]
    ax.add_patch(Circle(start[:2], max(model.radius, 1e-3), color=START_COLOR, alpha=0.5,
                        label="start"))
    arrow = 0.04 * float(np.max(world.extent))
    ax.arrow(start[0], start[1], arrow * np.cos(start[2]), arrow * np.sin(start[2]),
             color=START_COLOR, width=0.1 * arrow, length_includes_head=True)
    if goal is not None and goal_radius is not None:
        ax.add_patch(Circle(np.asarray(goal, dtype=float), goal_radius, color=GOAL_COLOR,
                            alpha=0.35, label="goal region"))


def _outcome(result: KinoResult) -> str:
    reached = f"goal in {result.duration:.1f} s of driving" if result.solved else "no plan"
    return f"{result.planner}, seed {result.seed}: {reached}, {result.iterations:,} iterations"


def diffdrive_figure(world: World2D, result: KinoResult, model: DiffDrive,
                     goal: ArrayLike | None = None, goal_radius: float | None = None
                     ) -> Figure:
    """The plan on its world: tree arcs, centre path, wheel tracks, start and goal region
    (drawn when ``goal`` (2,) and ``goal_radius`` (m) are given), the legend beside."""
    fig = new_figure(map_figure_size(world, (1, 1), (LEGEND_ROOM, 0.0), 8.0))
    ax = fig.subplots()
    draw_diffdrive(ax, world, result, model, goal, goal_radius)
    fig.legend(handles=ax.get_legend_handles_labels()[0], loc="outside right upper",
               fontsize=8)
    ax.set_title(f"{world.name}\n{_outcome(result)}", fontsize=9)
    return finish(fig)


def diffdrive_controls_figure(result: KinoResult, model: DiffDrive) -> Figure:
    """Speed and wheel speeds (m/s) above, turn rate (rad/s) below, against time (s)."""
    t, v, omega, left, right = control_profile(result, model)
    fig = new_figure((9, 6))
    top, bottom = fig.subplots(2, 1, sharex=True)
    top.plot(t, v, color=PATH_COLOR, label="v (centre)")
    top.plot(t, left, color=LEFT_COLOR, linewidth=0.9, label="left wheel")
    top.plot(t, right, color=RIGHT_COLOR, linewidth=0.9, label="right wheel")
    for limit in (model.v_min, model.v_max):
        top.axhline(limit, color="grey", linestyle=":", linewidth=0.8)
    top.set_ylabel("speed (m/s)")
    top.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    bottom.plot(t, omega, color="tab:blue", label="omega")
    for limit in (-model.omega_max, model.omega_max):
        bottom.axhline(limit, color="grey", linestyle=":", linewidth=0.8)
    bottom.set_ylabel("turn rate omega (rad/s)")
    bottom.set_xlabel("time (s)")
    top.set_title(f"controls: {_outcome(result)}", fontsize=9)
    return finish(fig)


def biased_vs_unbiased_figure(world: World2D, biased_result: KinoResult,
                              unbiased_result: KinoResult, model: DiffDrive,
                              goal: ArrayLike | None = None, goal_radius: float | None = None
                              ) -> Figure:
    """Goal-biased and uniform sampling side by side (one above the other for a
    :data:`~quadnav.viz.topview.WIDE` map), iteration counts in the titles, one legend
    below."""
    grid = (2, 1) if world.extent[0] > WIDE * world.extent[1] else (1, 2)
    fig = new_figure(map_figure_size(world, grid, (0.0, 0.6), 12.0))
    axes = fig.subplots(*grid)
    for ax, result, label in ((axes[0], biased_result, "goal-biased"),
                              (axes[1], unbiased_result, "unbiased")):
        draw_diffdrive(ax, world, result, model, goal, goal_radius)
        ax.set_title(f"{label} sampling: {result.iterations:,} iterations, "
                     f"{len(result.tree_states):,} states\n{_outcome(result)}", fontsize=9)
    # One legend for both: the entries without the counts, which differ (the titles
    # give them).
    entries: dict = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            entries.setdefault(label.split(" (")[0], handle)
    fig.legend(list(entries.values()), list(entries), loc="outside lower center", ncol=6,
               fontsize=8)
    fig.suptitle(world.name, fontsize=10)
    return finish(fig)
