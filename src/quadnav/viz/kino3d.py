"""Figures of a quadrotor kinodynamic plan: the tree and path in 3D, the control profiles.

Tree edges and the path are drawn as the parabolas the vehicle flies (each edge cut into
a few chords), not as straight lines between states.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.kinodynamic.pointmass import SampledQuadrotor, exact_positions
from quadnav.kinodynamic.result import KinoResult
from quadnav.viz.figures import new_figure
from quadnav.viz.layout import finish
from quadnav.viz.lines import draw_polylines
from quadnav.viz.map3d import draw_world, map_legend
from quadnav.viz.style import FLOWN_COLOR, PATH_COLOR, TREE_COLOR, outlined
from quadnav.viz.thinning import evenly_spread
from quadnav.world.model import World

#: Chord segments drawn for the tree at most; a larger tree is thinned evenly.
MAX_TREE_SEGMENTS = 20_000
#: Chords per tree edge, and per path edge.
TREE_PIECES = 4
PATH_PIECES = 16


def _motions(model: SampledQuadrotor, states: FloatArray, controls: FloatArray,
             durations: FloatArray, pieces: int) -> FloatArray:
    """Positions (E, pieces + 1, 3) along E exact motions from states (E, 6)."""
    times = durations[:, None] * np.linspace(0.0, 1.0, pieces + 1)
    return exact_positions(states, model.acceleration(controls), times)


def quadrotor_figure(world: World, result: KinoResult, model: SampledQuadrotor,
                     goal: ArrayLike | None = None, flown: ArrayLike | None = None
                     ) -> Figure:
    """The world with the tree's parabolas in a light colour, the planned flight in red
    (outlined, so that it shows on red blocks), start and goal spheres, the legend
    beside; the title gives the outcome and search statistics.

    Args:
        world: the map, blocks not inflated.
        result: a plan of :func:`~quadnav.kinodynamic.quadrotor.plan_quadrotor`.
        model: the vehicle it was planned for (to redraw the parabolas).
        goal: (3,) goal position, m; default the end of the path (none if unsolved).
        flown: (N, 3) positions, m, of the plan flown closed loop
            (:func:`~quadnav.kinoflight.fly_kino_plan`), drawn dashed when the plan is
            solved.
    """
    fig = new_figure((10, 7))
    ax = fig.add_subplot(projection="3d")
    if goal is None and result.solved:
        goal = result.states[-1, :3]
    handles = draw_world(ax, world, result.tree_states[0, :3], goal)
    children = np.flatnonzero(result.tree_parents >= 0)
    if children.size:
        shown = evenly_spread(children, MAX_TREE_SEGMENTS // TREE_PIECES)
        points = _motions(model, result.tree_states[result.tree_parents[shown]],
                          result.tree_controls[shown], result.tree_durations[shown],
                          TREE_PIECES)
        draw_polylines(ax, points, color=TREE_COLOR, linewidth=0.4, zorder=5)
        label = f"tree ({children.size:,} edges" + (
            f", {shown.size:,} drawn)" if shown.size < children.size else ")")
        handles.append(Line2D([], [], color=TREE_COLOR[:3], label=label))
    if flown is not None and result.solved:
        flown = np.asarray(flown, dtype=np.float64)
        ax.plot(*flown.T, color=FLOWN_COLOR, linewidth=1.4, linestyle="--", zorder=25)
        handles.append(Line2D([], [], color=FLOWN_COLOR, linewidth=1.4, linestyle="--",
                              label="flown closed loop"))
    if result.solved:
        path = _motions(model, result.states[:-1], result.controls, result.durations,
                        PATH_PIECES)
        handles += ax.plot(*np.concatenate([path[:, :-1].reshape(-1, 3),
                                            result.states[-1:, :3]]).T,
                           color=PATH_COLOR, linewidth=2.2, zorder=20,
                           path_effects=outlined(2.2), label=f"plan ({result.duration:.2f} s)")
    ax.view_init(elev=30, azim=-60)
    map_legend(fig, world, handles)
    outcome = (f"{len(result.controls)} controls, {result.duration:.2f} s" if result.solved
               else "goal not reached")
    ax.set_title(f"{world.name}\n{result.planner}, seed {result.seed}: {outcome}, "
                 f"{len(result.tree_states):,} states, {result.iterations:,} iterations in "
                 f"{result.seconds:.2f} s", fontsize=9)
    return finish(fig)


def quadrotor_controls_figure(result: KinoResult, model: SampledQuadrotor | None = None
                              ) -> Figure:
    """Roll and pitch (degrees) and thrust (N) against time as step plots, and the speed
    (m/s); with ``model``, its limits as dashed lines and the hover thrust dotted."""
    fig = new_figure((8, 8))
    axes = fig.subplots(4, 1, sharex=True)
    if not result.solved:
        axes[0].set_title(f"{result.planner}: goal not reached, no controls", fontsize=9)
        return finish(fig)
    knots = np.concatenate([[0.0], np.cumsum(result.durations)])
    # A held control is drawn to the end of its interval: repeat the last one at the end.
    held = np.vstack([result.controls, result.controls[-1:]])
    rows = [(np.degrees(held[:, 0]), "roll phi (deg)"),
            (np.degrees(held[:, 1]), "pitch theta (deg)"),
            (held[:, 2], "thrust T (N)")]
    for ax, (values, label) in zip(axes, rows, strict=False):
        ax.step(knots, values, where="post", color="tab:blue", linewidth=1.2)
        ax.set_ylabel(label)
    # Velocity is linear in time on each edge: sample it between the planned states.
    fractions = np.linspace(0.0, 1.0, 17)[:, None]
    v0, v1 = result.states[:-1, None, 3:], result.states[1:, None, 3:]
    speeds = np.linalg.norm(v0 + fractions * (v1 - v0), axis=2)  # (K - 1, 17)
    times = knots[:-1, None] + result.durations[:, None] * fractions[:, 0]
    axes[3].plot(times.ravel(), speeds.ravel(), color="tab:blue", linewidth=1.2)
    axes[3].set_ylabel("speed (m/s)")
    axes[3].set_xlabel("time (s)")
    if model is not None:
        roll, pitch = np.degrees(model.max_roll), np.degrees(model.max_pitch)
        bounds = [(-roll, roll), (-pitch, pitch), (model.min_thrust, model.max_thrust),
                  (model.speed_limit,)]
        for ax, values in zip(axes, bounds, strict=True):
            for value in values:
                if value is not None:
                    ax.axhline(value, color="gray", linestyle="--", linewidth=0.8)
        axes[2].axhline(model.hover_thrust, color="gray", linestyle=":", linewidth=0.8)
    axes[0].set_title(f"{result.planner}, seed {result.seed}: {len(result.controls)} controls "
                      f"over {result.duration:.2f} s", fontsize=9)
    return finish(fig)
