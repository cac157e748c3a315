"""Colours and sizes shared by every picture (matplotlib figures, the HTML viewer, the
animation and the Blender scene), so a path is the same red everywhere. Matplotlib colour
specs; RGBA tuples in [0, 1]."""

from __future__ import annotations

from matplotlib.patheffects import AbstractPathEffect, Normal, Stroke

TREE_COLOR = (0.35, 0.55, 0.85, 0.6)
PATH_COLOR = "red"
START_COLOR = "red"
GOAL_COLOR = "green"
TRAJECTORY_COLOR = "tab:orange"
FLOWN_COLOR = "black"
#: The true track of a real drone's flight, where it is known (the emulator's).
TRUTH_COLOR = "tab:purple"
COLLISION_COLOR = "magenta"
DRONE_COLOR = "tab:purple"
#: Drawn size of the drone marker relative to the map's largest extent.
DRONE_SCALE = 0.03
#: x, y, z.
AXIS_COLORS = ("tab:red", "tab:green", "tab:blue")
#: Motors 1 to 4: colours, and line styles that keep two equal commands both visible.
MOTOR_COLORS = ("tab:purple", "tab:orange", "tab:olive", "tab:cyan")
MOTOR_STYLES = ("-", "--", "-.", ":")
#: Marks of a step response.
STEP_COLOR = "tab:purple"
#: Widths, points, of the two edges of an outlined line: white inside, black outside.
OUTLINE_WIDTHS = (1.0, 0.8)


def outlined(width: float) -> list[AbstractPathEffect]:
    """Path effects (matplotlib's ``path_effects``) that edge a line ``width`` points wide
    in white, then black, so that it stands out on blocks of any colour: RBE595 maps
    colour every block red, as red as the path."""
    white, black = OUTLINE_WIDTHS
    return [Stroke(linewidth=width + 2 * (white + black), foreground="black"),
            Stroke(linewidth=width + 2 * white, foreground="white"), Normal()]
