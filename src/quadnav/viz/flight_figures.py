"""Figures of a run folder read back (:class:`~quadnav.runs.Run`, of ``quadnav
fly`` or ``quadnav track``): the run over the map (in 3D and from above), desired against
actual states (with a step's response marked), the position tracking error against time,
and the attitude and motor commands. Legends stand outside the plots.

Every consumer (``quadnav fly``, the report, the viewer) draws from the files a run
wrote, so a figure always shows what the folder holds.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from quadnav.runs import DRIFT_FIGURE, FIGURES, FlightTable, Run, drift, run_outcome
from quadnav.sim.flight import Ending
from quadnav.sim.step_response import SETTLING_BAND
from quadnav.vehicle.quaternion import euler_angles
from quadnav.viz.figures import new_figure
from quadnav.viz.layout import finish
from quadnav.viz.map3d import map_legend
from quadnav.viz.plan_figure import draw_tree
from quadnav.viz.style import (
    AXIS_COLORS,
    COLLISION_COLOR,
    FLOWN_COLOR,
    MOTOR_COLORS,
    MOTOR_STYLES,
    PATH_COLOR,
    STEP_COLOR,
    TRAJECTORY_COLOR,
    TRUTH_COLOR,
    outlined,
)
from quadnav.viz.topview import draw_fence_top, draw_map, plot_points, two_views

CM_PER_M = 100.0
#: Least height of a states plot's y range, m or m/s, so that an axis barely moving is
#: drawn flat instead of magnifying round-off.
MIN_SPAN = 0.2
#: Font sizes, points: legends and notes, titles. The figures are drawn at 120 dpi to be
#: shown about 1100 pixels wide (the report's width).
SMALL_FONT = 9
TITLE_FONT = 10
#: Height of the tracking error plot over the largest error, for the note.
HEADROOM = 1.15
#: Least height of an attitude plot's y range, degrees.
MIN_ANGLE_SPAN = 2.0


def _draw_run(ax: Axes, run: Run) -> list:
    """The map, tree, path, trajectory and flown track (and a collision marker) on a 3D
    axes or, seen from above, on a 2D one, whichever the run has; returns the legend
    handles."""
    world, metrics, flight = run.world, run.metrics, run.flight
    handles = draw_map(ax, world, world.start, world.goal)
    tree = draw_tree(ax, run.tree_edges())
    if tree is not None:
        handles.append(tree)
    if run.path is not None:
        handles += plot_points(ax, run.path, color=PATH_COLOR, linewidth=1.6, linestyle="--",
                               zorder=20, path_effects=outlined(1.6),
                               label=f"path ({metrics['path_length_m']:.2f} m, "
                                     f"{len(run.path)} waypoints)")
    if run.trajectory is not None:
        handles += plot_points(ax, run.trajectory.position, color=TRAJECTORY_COLOR,
                               linewidth=2.6, alpha=0.85, zorder=21,
                               label=f"{'reference' if run.is_track else 'trajectory'} "
                                     f"({run.trajectory.t[-1]:.2f} s)")
    if flight is not None:
        handles += plot_points(ax, flight.position, color=FLOWN_COLOR, linewidth=1.0,
                               zorder=22,
                               label=f"flown{', dead reckoning' if run.is_hardware else ''} "
                                     f"({flight.t[-1]:.2f} s)")
        if run.truth is not None:
            handles += plot_points(ax, run.truth[:, 1:4], color=TRUTH_COLOR, linewidth=1.0,
                                   zorder=22, label="true track")
        if metrics["ending"] == Ending.COLLISION.value:
            handles += plot_points(ax, flight.position[-1:], color=COLLISION_COLOR,
                                   marker="X", markersize=13, markeredgecolor="black",
                                   linestyle="", zorder=30,
                                   label=f"collision (block {metrics['contact_block']}, "
                                         f"{metrics['contact_time_s']:.2f} s)")
    return handles


def flight_3d_figure(run: Run) -> Figure:
    """The map, the explored tree, the path (red, dashed, outlined), the trajectory and
    the flown track (a real drone's: also its true track, when known) seen obliquely (3D)
    and from above (2D, to scale), a cross where a
    collision stopped the flight, one legend below both; the title gives the map (a
    track: the reference), the outcome, the RMS tracking error (a real drone's: from
    the planned route, and its geofence dotted in the top view) and the top speed (not
    for a track). A run without a path shows the map and the tree."""
    metrics = run.metrics
    fig, oblique, top = two_views(run.world, (12, 7))
    handles = _draw_run(oblique, run)
    _draw_run(top, run)
    if run.is_hardware:  # where the bridge kept the drone
        handles.append(draw_fence_top(top, run.world, run.metrics["margin_m"]))
    map_legend(fig, run.world, handles, loc="outside lower center", ncol=3,
               fontsize=SMALL_FONT)
    summary = run_outcome(metrics)
    if run.flight is not None:
        error = CM_PER_M * metrics["rms_tracking_error_m"]
        summary += (f": dead-reckoned track {error:.2f} cm RMS from the planned route"
                    if run.is_hardware else f": RMS tracking error {error:.2f} cm")
        if not run.is_track:
            summary += f", top speed {metrics['speed_m_s']:g} m/s"
    fig.suptitle(f"{run.title}\n{summary}", fontsize=TITLE_FONT)
    return finish(fig)


def _widen(ax: Axes, span: float) -> None:
    """Widen ``ax``'s y range about its middle to at least ``span``."""
    low, high = ax.get_ylim()
    if high - low < span:
        middle = (low + high) / 2
        ax.set_ylim(middle - span / 2, middle + span / 2)


def _flight(run: Run) -> FlightTable:
    if run.flight is None:
        raise ValueError(f"{run.folder}: the run has no flight (no path was found)")
    return run.flight


def _desired(run: Run, name: str) -> np.ndarray:
    """trajectory.csv's column(s) ``name`` (a field of
    :class:`~quadnav.trajectory.references.contract.Samples`: (N,) or (N, 3)) at the flight's sample
    times, linearly interpolated (held at the last after its end)."""
    flight, trajectory = _flight(run), run.trajectory
    values = getattr(trajectory, name)
    if values.ndim == 1:
        return np.interp(flight.t, trajectory.t, values)
    return np.column_stack([np.interp(flight.t, trajectory.t, column) for column in values.T])


def desired_velocity(run: Run) -> np.ndarray:
    """(N, 3) the reference velocity at the flight's sample times, m/s: trajectory.csv's
    velocity linearly interpolated (held at its last value, rest, after its end)."""
    return _desired(run, "velocity")


def desired_acceleration(run: Run) -> np.ndarray:
    """(N, 3) the reference acceleration at the flight's sample times, m/s^2, as
    :func:`desired_velocity`."""
    return _desired(run, "acceleration")


def actual_acceleration(flight: FlightTable) -> np.ndarray:
    """(N, 3) the flown acceleration, m/s^2: the recorded velocity's finite differences
    (second order, at the possibly uneven sample times)."""
    if len(flight.t) < 2:
        return np.zeros_like(flight.velocity)
    return np.gradient(flight.velocity, flight.t, axis=0)


def flight_states_figure(run: Run) -> Figure:
    """Desired (dashed) against actual (solid) position, velocity and acceleration per
    axis against time: rows x, y, z; columns position (m), velocity (m/s), acceleration
    (m/s^2); one legend below. The desired position is flight.csv's reference, the desired
    velocity and acceleration trajectory.csv's (:func:`desired_velocity`); the actual
    acceleration is :func:`actual_acceleration`. A step's response is marked on its
    axis (:func:`_mark_step`)."""
    flight = _flight(run)
    fig = new_figure((13, 8))
    axes = fig.subplots(3, 3, sharex=True)
    columns = (("position", "", "m", flight.reference, flight.position),
               ("velocity", "v", "m/s", desired_velocity(run), flight.velocity),
               ("acceleration", "a", "m/s²", desired_acceleration(run),
                actual_acceleration(flight)))
    for column, (name, prefix, unit, desired, actual) in enumerate(columns):
        for axis, color in enumerate(AXIS_COLORS):
            ax = axes[axis, column]
            ax.plot(flight.t, desired[:, axis], color="0.1", linestyle="--", linewidth=1.0,
                    label="desired", zorder=3)  # dashed over the actual, so both show
            ax.plot(flight.t, actual[:, axis], color=color, linewidth=1.6, label="actual")
            _widen(ax, MIN_SPAN)
            ax.set_ylabel(f"{prefix}{'xyz'[axis]} ({unit})")
            ax.grid(alpha=0.3)
        axes[0, column].set_title(name, fontsize=TITLE_FONT)
        axes[-1, column].set_xlabel("time (s)")
    handles = [Line2D([], [], color="0.1", linestyle="--", linewidth=1.0, label="desired"),
               *(Line2D([], [], color=color, linewidth=1.6, label=f"actual {name}")
                 for name, color in zip("xyz", AXIS_COLORS, strict=True))]
    handles += _mark_step(axes[:, 0], run.metrics)
    fig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=SMALL_FONT)
    fig.suptitle(f"desired and actual states: {run.metrics['ending']} after "
                 f"{flight.t[-1]:.2f} s", fontsize=TITLE_FONT)
    return finish(fig)


def _mark_step(position_axes: np.ndarray, metrics: dict) -> list:
    """On the position plot of a step's axis (``position_axes``: x, y, z), the settling
    band about the target (shaded), where it settled (a dotted line) and the peak (a
    dot); returns their legend handles, which give the step metrics (none but for a
    step)."""
    if "overshoot_percent" not in metrics:
        return []
    axis = "xyz".index(metrics["step_axis"])
    ax, size = position_axes[axis], metrics["step_size_m"]
    target, band = metrics["goal"][axis], SETTLING_BAND * abs(size)
    ax.axhspan(target - band, target + band, color=STEP_COLOR, alpha=0.25, linewidth=0,
               zorder=1)
    handles = [Patch(color=STEP_COLOR, alpha=0.25,
                     label=f"{100 * SETTLING_BAND:g} % band about the target")]
    line = next(line for line in ax.get_lines() if line.get_label() == "actual")
    t, x = line.get_xdata(), line.get_ydata()
    along = np.where(t >= metrics["step_time_s"], np.sign(size) * x, -np.inf)
    peak = int(np.argmax(along))  # the farthest along the step, after it
    ax.plot(t[peak], x[peak], marker="o", color=STEP_COLOR, markeredgecolor="black",
            linestyle="", zorder=4)
    handles.append(Line2D([], [], marker="o", color=STEP_COLOR, markeredgecolor="black",
                          linestyle="", label=f"peak: overshoot "
                                              f"{metrics['overshoot_percent']:.2f} %"))
    settling = metrics["settling_time_s"]
    if settling is not None:
        settled = metrics["step_time_s"] + settling
        ax.axvline(settled, color=STEP_COLOR, linestyle=":", linewidth=1.4, zorder=2)
        handles.append(Line2D([], [], color=STEP_COLOR, linestyle=":", linewidth=1.4,
                              label=f"settled at {settled:.2f} s ({settling:.2f} s after "
                                    "the step)"))
    rise = metrics["rise_time_s"]
    handles.append(Line2D([], [], linestyle="", label=(
        f"rise (10-90 %) {'-' if rise is None else f'{rise:.2f} s'}, steady-state error "
        f"{CM_PER_M * metrics['steady_state_error_m']:.2f} cm")))
    return handles


def tracking_error(flight: FlightTable) -> np.ndarray:
    """(N,) distance from the reference position at each recorded sample, m."""
    return np.linalg.norm(flight.position - flight.reference, axis=1)


def tracking_error_figure(run: Run) -> Figure:
    """The distance from the reference position against time, cm, with the RMS as a
    dashed line and the largest recorded error marked, the legend beside; the RMS and
    maximum over every control step (metrics.json) are in the title. For a real drone's
    run the reference is the nearest point of the planned route, at every state packet."""
    flight, metrics = _flight(run), run.metrics
    error = CM_PER_M * tracking_error(flight)
    rms = CM_PER_M * metrics["rms_tracking_error_m"]
    duration = flight.t[-1]
    fig = new_figure((10, 4))
    ax = fig.subplots()
    ax.plot(flight.t, error, color="tab:blue", linewidth=1.2, label="tracking error")
    ax.axhline(rms, color="black", linestyle="--", linewidth=0.8, label=f"RMS {rms:.2f} cm")
    peak = int(np.argmax(error))
    ax.plot(flight.t[peak], error[peak], color="tab:red", marker="o", linestyle="",
            label="_max")
    left = flight.t[peak] <= 0.5 * duration  # the label goes on the roomier side
    ax.annotate(f"max {error[peak]:.2f} cm at {flight.t[peak]:.2f} s",
                (flight.t[peak], error[peak]), xytext=(8 if left else -8, 4),
                textcoords="offset points", fontsize=SMALL_FONT,
                ha="left" if left else "right")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("position error (cm)")
    ax.set_ylim(bottom=0.0, top=HEADROOM * max(float(error.max()), rms, 1e-6))
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=SMALL_FONT)
    what, over = (("distance from the planned route", "state packet") if run.is_hardware
                  else ("position tracking error", "control step"))
    ax.set_title(f"{what} ({metrics['ending']} after {duration:.2f} s)\n"
                 f"over every {over}: RMS {rms:.2f} cm, "
                 f"max {CM_PER_M * metrics['max_tracking_error_m']:.2f} cm",
                 fontsize=TITLE_FONT)
    return finish(fig)


def attitude_motors_figure(run: Run) -> Figure:
    """Roll, pitch and yaw (degrees, from flight.csv's attitude; the yaw reference of
    trajectory.csv dashed) and the four motor commands (in [0, 1]) against time, one
    legend below."""
    flight = _flight(run)
    fig = new_figure((11, 9))
    axes = fig.subplots(4, 1, sharex=True)
    angles = np.degrees(euler_angles(flight.attitude))
    angles[:, 2] = np.degrees(np.unwrap(np.radians(angles[:, 2])))
    reference_yaw = np.degrees(np.unwrap(_desired(run, "yaw")))
    for ax, name, values, color in zip(axes, ("roll", "pitch", "yaw"), angles.T, AXIS_COLORS,
                                       strict=False):
        ax.plot(flight.t, values, color=color, linewidth=1.4, label=f"actual {name}")
        ax.set_ylabel(f"{name} (deg)")
        ax.grid(alpha=0.3)
        _widen(ax, MIN_ANGLE_SPAN)
    axes[2].plot(flight.t, reference_yaw, color="0.1", linestyle="--", linewidth=1.0,
                 label="yaw reference", zorder=3)
    _widen(axes[2], MIN_ANGLE_SPAN)
    for motor, (color, style) in enumerate(zip(MOTOR_COLORS, MOTOR_STYLES, strict=True)):
        axes[3].plot(flight.t, flight.commands[:, motor], color=color, linestyle=style,
                     linewidth=1.2, label=f"motor {motor + 1}")
    axes[3].set_ylim(-0.05, 1.05)
    axes[3].set_ylabel("motor command")
    axes[3].set_xlabel("time (s)")
    axes[3].grid(alpha=0.3)
    handles = [handle for ax in axes for handle in ax.get_legend_handles_labels()[0]]
    fig.legend(handles=handles, loc="outside lower center", ncol=4, fontsize=SMALL_FONT)
    fig.suptitle(f"attitude and motor commands: {run.metrics['ending']} after "
                 f"{flight.t[-1]:.2f} s", fontsize=TITLE_FONT)
    return finish(fig)


def drift_figure(run: Run) -> Figure:
    """A real drone's run with a true track: the horizontal distance from the estimate to
    the truth against time, cm (:func:`~quadnav.runs.drift`), with the 1-sigma stated for
    the landing dashed and the drift at the landing, RMS and largest in the title."""
    flight, metrics = _flight(run), run.metrics
    drifts = CM_PER_M * drift(flight, run.truth)
    fig = new_figure((10, 4))
    ax = fig.subplots()
    ax.plot(flight.t, drifts, color=TRUTH_COLOR, linewidth=1.2,
            label="estimate's distance from the truth")
    sigma, landing = metrics.get("landing_sigma_m"), metrics.get("landing_drift_m")
    top = float(drifts.max())
    if sigma is not None:
        ax.axhline(CM_PER_M * sigma, color="black", linestyle="--", linewidth=0.8,
                   label=f"1-sigma stated at the landing ({CM_PER_M * sigma:.2f} cm)")
        top = max(top, CM_PER_M * sigma)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("horizontal drift (cm)")
    ax.set_ylim(bottom=0.0, top=HEADROOM * max(top, 1e-6))
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=SMALL_FONT)
    at_landing = "" if landing is None else f"{CM_PER_M * landing:.2f} cm at the landing, "
    ax.set_title(f"dead-reckoned estimate against the true track ({metrics['ending']})\n"
                 f"drift {at_landing}RMS {CM_PER_M * metrics['rms_drift_m']:.2f} cm, max "
                 f"{CM_PER_M * metrics['max_drift_m']:.2f} cm over every state packet",
                 fontsize=TITLE_FONT)
    return finish(fig)


def figure_makers(run: Run) -> dict[str, Callable[[Run], Figure]]:
    """The figures ``run`` has, by their file name in the run folder, in the order of
    :data:`~quadnav.runs.FIGURES`: the 3D view always, the states, the tracking
    error and the attitude and motors when there was a flight (of a real drone's flight,
    the tracking error alone, and with a true track the drift from it,
    :data:`~quadnav.runs.DRIFT_FIGURE`: see :mod:`quadnav.hardware.bridge.run_record`)."""
    makers = dict(zip(FIGURES, (flight_3d_figure, flight_states_figure,
                                tracking_error_figure, attitude_motors_figure), strict=True))
    if run.flight is None:
        return {FIGURES[0]: flight_3d_figure}
    if run.is_hardware:  # a tracked position: no timed reference, no motor commands
        hardware = {name: makers[name] for name in (FIGURES[0], FIGURES[2])}
        return hardware | ({DRIFT_FIGURE: drift_figure} if run.truth is not None else {})
    return makers
