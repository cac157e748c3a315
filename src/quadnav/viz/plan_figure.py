"""The figure of a planning result: the world, the explored tree, the path in red."""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from quadnav.planning.problem import PlanningProblem
from quadnav.planning.result import PlanResult
from quadnav.viz.figures import new_figure
from quadnav.viz.layout import finish
from quadnav.viz.lines import draw_polylines
from quadnav.viz.map3d import draw_world, map_legend
from quadnav.viz.style import PATH_COLOR, TREE_COLOR, outlined
from quadnav.viz.thinning import evenly_spread

#: Tree edges drawn at most; a larger tree is thinned to an evenly spread subset.
MAX_TREE_EDGES = 20_000


def draw_tree(ax: Axes, edges: np.ndarray) -> Line2D | None:
    """Draw a search tree's edges (E, 2, 3), m, in a light colour on a 3D axes (or seen
    from above on a 2D one), thinned to at most :data:`MAX_TREE_EDGES` evenly spread
    ones; returns a legend handle giving the counts (None, and nothing drawn, for no
    edges)."""
    if not len(edges):
        return None
    shown = evenly_spread(edges, MAX_TREE_EDGES)
    draw_polylines(ax, shown, color=TREE_COLOR, linewidth=0.4, zorder=5)
    label = f"tree ({len(edges):,} edges" + (
        f", {len(shown):,} drawn)" if len(shown) < len(edges) else ")")
    return Line2D([], [], color=TREE_COLOR[:3], label=label)


def plan_figure(problem: PlanningProblem, result: PlanResult) -> Figure:
    """The world with the explored tree in a light colour, the path in red (outlined, so
    that it shows on red blocks), start and goal spheres, the legend beside; the title
    gives the planner, length and search statistics."""
    fig = new_figure((10, 7))
    ax = fig.add_subplot(projection="3d")
    handles = draw_world(ax, problem.world, problem.start, problem.goal)
    tree = draw_tree(ax, result.tree_edges())
    if tree is not None:
        handles.append(tree)
    if result.solved:
        handles += ax.plot(*result.path.T, color=PATH_COLOR, linewidth=2.2, zorder=20,
                           path_effects=outlined(2.2), label=f"path ({result.length:.2f} m)")
    ax.view_init(elev=30, azim=-60)
    map_legend(fig, problem.world, handles)
    outcome = f"{result.length:.2f} m" if result.solved else "no path"
    ax.set_title(f"{problem.world.name}\n{result.planner}, seed {result.seed}: {outcome}, "
                 f"{result.stats.nodes:,} nodes in {result.stats.seconds:.2f} s", fontsize=9)
    return finish(fig)
