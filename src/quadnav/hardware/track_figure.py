"""The figure of a Tello flight: the map, what was planned and the tracks flown.

Drawn in two views (oblique and from above, as ``quadnav fly``'s flight figure): the
planned track from takeoff to landing (through the ``go`` moves' targets, or along the
trajectory), and each flown track given — the dead-reckoned estimate from the state
packets, and in tests the emulator's true track.
"""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

from quadnav.hardware.flight_plan import FlightPlan
from quadnav.hardware.frames import FloatArray
from quadnav.viz.flight_figures import FLOWN_COLOR, TITLE_FONT, TRAJECTORY_COLOR, VIEWS
from quadnav.viz.map3d import draw_world

#: Colours of the flown tracks, in the order given.
TRACK_COLORS = (FLOWN_COLOR, "tab:purple", "tab:cyan")


def track_figure(plan: FlightPlan, mode: str, flown: Mapping[str, FloatArray],
                 outcome: str) -> Figure:
    """The map with the planned track of ``mode`` and the ``flown`` tracks ((N, 3) map
    positions, m, by label), titled with the map, the mode and the ``outcome``."""
    fig = plt.figure(figsize=(13, 6.5), dpi=120)
    planned = plan.planned_points(mode)
    world = plan.fence.world
    for column, (view, elevation, azimuth) in enumerate(VIEWS, 1):
        ax = fig.add_subplot(1, 2, column, projection="3d")
        handles = draw_world(ax, world, plan.problem.start, plan.problem.goal)
        handles += ax.plot(*planned.T, color=TRAJECTORY_COLOR, linewidth=2.4, alpha=0.85,
                           zorder=20, label=f"planned ({mode})")
        for (label, track), color in zip(flown.items(), TRACK_COLORS, strict=False):
            if len(track):
                handles += ax.plot(*track.T, color=color, linewidth=1.2, zorder=22,
                                   label=label)
        ax.view_init(elev=elevation, azim=azimuth)
        ax.set_title(view, fontsize=TITLE_FONT)
        if column == 1:
            ax.legend(handles=handles, loc="upper left", fontsize=8)
    fig.suptitle(f"{world.name}: Tello, {mode} mode — {outcome}", fontsize=TITLE_FONT)
    fig.tight_layout()
    return fig
