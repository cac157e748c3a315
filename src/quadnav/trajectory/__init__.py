"""Trajectory stage: smooth, timed references through waypoints (a planner's path).

* :class:`Trajectory` — a piecewise polynomial per axis with a yaw reference.
"""

from quadnav.trajectory.model import Samples, Trajectory, YawMode, ppoly_from_ascending

__all__ = ["Samples", "Trajectory", "YawMode", "ppoly_from_ascending"]
