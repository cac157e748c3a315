"""Figures of a simulated flight: the mission over the map in 3D, desired against actual
states, and the position tracking error against time."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from mpl_toolkits.mplot3d import Axes3D

from quadnav.mission import Mission
from quadnav.sim.flight import Ending, Flight
from quadnav.viz.map3d import draw_world
from quadnav.viz.plan_figure import PATH_COLOR, draw_tree
from quadnav.viz.trajectory_figures import AXIS_COLORS

#: Sample spacing of the drawn trajectory, s.
TRAJECTORY_STEP = 0.02
TRAJECTORY_COLOR = "tab:orange"
FLOWN_COLOR = "black"
COLLISION_COLOR = "magenta"
#: The two views of :func:`flight_3d_figure`: title, elevation and azimuth, degrees.
VIEWS = (("oblique view", 30.0, -60.0), ("top view", 90.0, -90.0))
CM_PER_M = 100.0
#: Least height of a states plot's y range, m or m/s, so that an axis barely moving is
#: drawn flat instead of magnifying round-off.
MIN_SPAN = 0.2


def mission_outcome(mission: Mission) -> str:
    """``success``, or why the flight failed: its ending and when, or the goal missed."""
    flight = mission.flight
    if flight is None:
        return "not flown"
    if mission.success:
        return "success"
    if flight.ending is Ending.COMPLETED:
        return f"goal missed by {flight.final_error:.2f} m"
    return f"{flight.ending.value} at {flight.contact_time:.2f} s"


def _draw_mission(ax: Axes3D, mission: Mission) -> list:
    """The map, tree, path, trajectory and flown track (and a collision marker) on one
    3D axes; returns the legend handles."""
    problem, flight, trajectory = mission.problem, mission.flight, mission.trajectory
    handles = draw_world(ax, problem.world, problem.start, problem.goal)
    tree = draw_tree(ax, mission.plan.tree_edges())
    if tree is not None:
        handles.append(tree)
    path = mission.plan.path
    handles += ax.plot(*path.T, color=PATH_COLOR, linewidth=1.4, linestyle="--", zorder=20,
                       label=f"path ({mission.plan.length:.2f} m, {len(path)} waypoints)")
    handles += ax.plot(*trajectory.sample(TRAJECTORY_STEP).position.T, color=TRAJECTORY_COLOR,
                       linewidth=2.6, alpha=0.85, zorder=21,
                       label=f"trajectory ({trajectory.duration:.2f} s)")
    handles += ax.plot(*flight.position.T, color=FLOWN_COLOR, linewidth=1.0, zorder=22,
                       label=f"flown ({flight.duration:.2f} s)")
    if flight.ending is Ending.COLLISION:
        handles += ax.plot(*flight.position[-1:].T, color=COLLISION_COLOR, marker="X",
                           markersize=13, markeredgecolor="black", linestyle="", zorder=30,
                           label=f"collision (block {flight.contact_block}, "
                                 f"{flight.contact_time:.2f} s)")
    return handles


def flight_3d_figure(mission: Mission) -> Figure:
    """The map, the explored tree, the path (red, dashed), the trajectory and the flown
    track seen obliquely and from above, a cross where a collision stopped the flight;
    the title gives the map, the outcome, the RMS tracking error and the cruise speed.

    ``mission.trajectory`` and ``mission.flight`` must not be None.
    """
    flight = mission.flight
    fig = plt.figure(figsize=(15, 7.5), dpi=120)
    for column, (title, elev, azim) in enumerate(VIEWS):
        ax = fig.add_subplot(1, 2, column + 1, projection="3d")
        handles = _draw_mission(ax, mission)
        ax.view_init(elev=elev, azim=azim)
        if elev == 90.0:  # a plan view: no perspective, and no height axis to read
            ax.set_proj_type("ortho")
            ax.set_zticks([])
            ax.set_zlabel("")
        ax.set_title(title, fontsize=9)
        if column == 0:
            ax.legend(handles=handles, loc="upper left", fontsize=8)
    fig.suptitle(f"{mission.problem.world.name}\n{mission_outcome(mission)}: RMS tracking error "
                 f"{CM_PER_M * flight.rms_tracking_error:.2f} cm, cruise speed "
                 f"{mission.settings.trajectory.v_max:g} m/s", fontsize=9)
    fig.tight_layout()
    return fig


def _widen(ax: Axes, span: float) -> None:
    """Widen ``ax``'s y range about its middle to at least ``span``."""
    low, high = ax.get_ylim()
    if high - low < span:
        middle = (low + high) / 2
        ax.set_ylim(middle - span / 2, middle + span / 2)


def flight_states_figure(flight: Flight) -> Figure:
    """Desired (dashed) against actual (solid) position and velocity per axis against
    time: rows x, y, z; columns position (m), velocity (m/s)."""
    fig, axes = plt.subplots(3, 2, figsize=(11, 8), dpi=120, sharex=True)
    columns = (("position", "m", flight.reference[:, 0:3], flight.position),
               ("velocity", "m/s", flight.reference[:, 3:6], flight.velocity))
    for column, (name, unit, desired, actual) in enumerate(columns):
        for axis, color in enumerate(AXIS_COLORS):
            ax = axes[axis, column]
            ax.plot(flight.t, desired[:, axis], color="0.1", linestyle="--", linewidth=1.0,
                    label="desired", zorder=3)  # dashed over the actual, so both show
            ax.plot(flight.t, actual[:, axis], color=color, linewidth=1.6, label="actual")
            _widen(ax, MIN_SPAN)
            symbol = "xyz"[axis]
            ax.set_ylabel(f"{symbol if column == 0 else 'v' + symbol} ({unit})")
            ax.grid(alpha=0.3)
        axes[0, column].set_title(name, fontsize=9)
        axes[0, column].legend(loc="upper right", fontsize=7, ncol=2)
        axes[-1, column].set_xlabel("time (s)")
    fig.suptitle(f"desired and actual states: {flight.ending.value} after "
                 f"{flight.duration:.2f} s", fontsize=9)
    fig.tight_layout()
    return fig


def tracking_error_figure(flight: Flight) -> Figure:
    """The distance from the reference position against time, cm, with the RMS as a
    dashed line and the largest recorded error marked."""
    error = CM_PER_M * flight.tracking_error
    rms = CM_PER_M * flight.rms_tracking_error
    fig, ax = plt.subplots(figsize=(9, 4), dpi=120)
    ax.plot(flight.t, error, color="tab:blue", linewidth=1.2, label="tracking error")
    ax.axhline(rms, color="black", linestyle="--", linewidth=0.8, label=f"RMS {rms:.2f} cm")
    peak = int(np.argmax(error))
    ax.plot(flight.t[peak], error[peak], color="tab:red", marker="o", linestyle="",
            label="_max")
    left = flight.t[peak] <= 0.5 * flight.duration  # the label goes on the roomier side
    ax.annotate(f"max {error[peak]:.2f} cm at {flight.t[peak]:.2f} s",
                (flight.t[peak], error[peak]), xytext=(8 if left else -8, 4),
                textcoords="offset points", fontsize=8, ha="left" if left else "right")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("position error (cm)")
    ax.set_ylim(bottom=0.0, top=1.15 * max(float(error.max()), rms, 1e-6))
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(f"position tracking error ({flight.ending.value} after "
                 f"{flight.duration:.2f} s); over every control step: RMS {rms:.2f} cm, "
                 f"max {CM_PER_M * flight.max_tracking_error:.2f} cm", fontsize=9)
    fig.tight_layout()
    return fig
