"""The figure of a Tello flight: the map, what was planned and the tracks flown.

Drawn in two views (as ``quadnav fly``'s flight figure): oblique in 3D, and from above
on a plain 2D axes, to scale. It shows the planned track from takeoff to landing
(through the ``go`` moves' targets, or along the trajectory), outlined so that it shows
on red blocks, and each flown track given — the dead-reckoned estimate from the state
packets, and in tests the emulator's true track. One legend stands below both views.
"""

from __future__ import annotations

from collections.abc import Mapping

from matplotlib.figure import Figure

from quadnav.arrays import FloatArray
from quadnav.hardware.bridge.flight_plan import FlightPlan
from quadnav.viz.flight_figures import FLOWN_COLOR, SMALL_FONT, TITLE_FONT, TRAJECTORY_COLOR
from quadnav.viz.layout import finish
from quadnav.viz.map3d import map_legend
from quadnav.viz.style import TRUTH_COLOR, outlined
from quadnav.viz.topview import draw_map, plot_points, two_views

#: Colours of the flown tracks, in the order given.
TRACK_COLORS = (FLOWN_COLOR, TRUTH_COLOR, "tab:cyan")


def track_figure(plan: FlightPlan, mode: str, flown: Mapping[str, FloatArray],
                 outcome: str) -> Figure:
    """The map with the planned track of ``mode`` and the ``flown`` tracks ((N, 3) map
    positions, m, by label), titled with the map, the mode and the ``outcome``."""
    planned = plan.planned_points(mode)
    world = plan.fence.world
    fig, oblique, top = two_views(world, (12, 7))
    for ax in (oblique, top):
        handles = draw_map(ax, world, plan.problem.start, plan.problem.goal)
        handles += plot_points(ax, planned, color=TRAJECTORY_COLOR, linewidth=2.4, zorder=20,
                               path_effects=outlined(2.4), label=f"planned ({mode})")
        for (label, track), color in zip(flown.items(), TRACK_COLORS, strict=False):
            if len(track):
                handles += plot_points(ax, track, color=color, linewidth=1.2, zorder=22,
                                       label=label)
    map_legend(fig, world, handles, loc="outside lower center", ncol=3, fontsize=SMALL_FONT)
    fig.suptitle(f"{world.name}: Tello, {mode} mode — {outcome}", fontsize=TITLE_FONT)
    return finish(fig)
