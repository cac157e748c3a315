"""Colours and sizes shared by every picture (matplotlib figures, the HTML viewer, the
animation and the Blender scene), so a path is the same red everywhere. Matplotlib colour
specs; RGBA tuples in [0, 1]."""

TREE_COLOR = (0.35, 0.55, 0.85, 0.35)
PATH_COLOR = "red"
START_COLOR = "red"
GOAL_COLOR = "green"
TRAJECTORY_COLOR = "tab:orange"
FLOWN_COLOR = "black"
COLLISION_COLOR = "magenta"
DRONE_COLOR = "tab:purple"
#: Drawn size of the drone marker relative to the map's largest extent.
DRONE_SCALE = 0.03
#: x, y, z.
AXIS_COLORS = ("tab:red", "tab:green", "tab:blue")
