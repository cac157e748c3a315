"""Figures of a trajectory: over the map in 3D, and its states against time."""

from __future__ import annotations

import numpy as np
from matplotlib.colors import Normalize
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from mpl_toolkits.mplot3d.art3d import Line3DCollection

from quadnav.trajectory.model import Trajectory
from quadnav.viz.figures import new_figure
from quadnav.viz.layout import finish
from quadnav.viz.map3d import draw_world, map_legend
from quadnav.viz.style import AXIS_COLORS, outlined
from quadnav.world.model import World

#: Samples per second drawn.
DRAW_RATE = 100.0


def trajectory_3d_figure(world: World, trajectory: Trajectory,
                         path: np.ndarray | None = None) -> Figure:
    """The map with the trajectory coloured by speed, its waypoints, and (dashed grey)
    the path it was made from; the colour bar and the legend beside."""
    fig = new_figure((10, 7))
    ax = fig.add_subplot(projection="3d")
    waypoints = trajectory.waypoints
    handles = draw_world(ax, world, waypoints[0], waypoints[-1])
    if path is not None:
        ax.plot(*np.asarray(path).T, color="0.4", linestyle="--", linewidth=1.0, zorder=15)
        handles.append(Line2D([], [], color="0.4", linestyle="--", label="path"))
    t = np.linspace(0.0, trajectory.duration, max(int(DRAW_RATE * trajectory.duration), 2))
    points = trajectory.position(t)
    speed = np.linalg.norm(trajectory.velocity(t), axis=1)
    lines = Line3DCollection(np.stack([points[:-1], points[1:]], axis=1), cmap="viridis",
                             norm=Normalize(0.0, max(float(speed.max()), 1e-9)),
                             linewidths=2.2, zorder=20)
    lines.set_array(0.5 * (speed[:-1] + speed[1:]))
    # Under the segments, the same line outlined, so the trajectory shows on any block.
    ax.plot(*points.T, color="white", linewidth=2.2, zorder=19, path_effects=outlined(2.2))
    ax.add_collection3d(lines)
    fig.colorbar(lines, ax=ax, shrink=0.6, label="speed (m/s)")
    ax.scatter(*waypoints.T, color="black", s=8, zorder=25, depthshade=False)
    handles.append(Line2D([], [], color="black", marker="o", markersize=3, linestyle="",
                          label=f"waypoints ({len(waypoints)})"))
    ax.view_init(elev=30, azim=-60)
    map_legend(fig, world, handles)
    ax.set_title(f"{world.name}\n{trajectory.method}: {trajectory.duration:.2f} s, "
                 f"top speed {speed.max():.2f} m/s", fontsize=9)
    return finish(fig)


def states_figure(trajectory: Trajectory, v_max: float | None = None,
                  a_max: float | None = None) -> Figure:
    """Position, velocity and acceleration against time (x, y, z and the norm of the
    latter two, with their limits dashed), one legend below; waypoint times are
    marked."""
    t = np.linspace(0.0, trajectory.duration, max(int(DRAW_RATE * trajectory.duration), 2))
    fig = new_figure((9, 8))
    axes = fig.subplots(3, 1, sharex=True)
    rows = (("position", "m", None), ("velocity", "m/s", v_max),
            ("acceleration", "m/s²", a_max))
    for order, (ax, (name, unit, limit)) in enumerate(zip(axes, rows, strict=True)):
        values = trajectory.derivative(t, order)
        for axis, color in enumerate(AXIS_COLORS):
            ax.plot(t, values[:, axis], color=color, linewidth=1.2, label="xyz"[axis])
        if order:
            ax.plot(t, np.linalg.norm(values, axis=1), color="black", linewidth=1.0,
                    label="norm")
        if limit is not None:
            ax.axhline(limit, color="black", linestyle="--", linewidth=0.8, label="limit")
        for when in trajectory.breaks:
            ax.axvline(when, color="0.85", linewidth=0.6, zorder=0)
        ax.set_ylabel(f"{name} ({unit})")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time (s)")
    fig.legend(handles=max((ax.get_legend_handles_labels()[0] for ax in axes), key=len),
               loc="outside lower center", ncol=5, fontsize=8)
    fig.suptitle(f"{trajectory.method}: {len(trajectory.waypoints)} waypoints "
                 "(grey lines), desired states", fontsize=9)
    return finish(fig)
