"""Trajectory stage: smooth, timed references through waypoints (a planner's path).

* :func:`make_trajectory` with :class:`TrajectorySettings` — the stage's entry point.
* :class:`SafeSpace` — the map and margin a trajectory keeps outside the legs out of the
  margin; :func:`trajectory_margins` measures the margin kept, exactly.
* :class:`Trajectory` — a piecewise polynomial per axis with a yaw reference.
* :class:`Reference` — what the simulation flies: a Trajectory or anything else with a
  position, velocity, acceleration and yaw over time (built-in shapes in
  :mod:`.references`, samples read from a file in :mod:`.sampled`, a plain-Python class in
  rotorpy's shape, ``update(t) -> flat outputs``, sampled in :mod:`.plain`).
* Generators ``(waypoints (N, 3), segment times (N - 1,)) -> Trajectory``:
  :func:`minimum_snap`, :func:`minimum_snap_qp`, :func:`quintic_segments`,
  :func:`quintic_c2`, :func:`quintic_average`, :func:`cubic_spline`.
* :func:`feasibility` — peaks against a vehicle's :class:`Limits`.
"""

from quadnav.trajectory.cubic import cubic_spline
from quadnav.trajectory.feasibility import FeasibilityReport, Limits, feasibility
from quadnav.trajectory.generate import (
    METHODS,
    TIMINGS,
    TrajectorySettings,
    make_trajectory,
)
from quadnav.trajectory.minsnap import minimum_snap, snap_cost
from quadnav.trajectory.minsnap_qp import minimum_snap_qp
from quadnav.trajectory.model import Trajectory, YawMode, ppoly_from_ascending
from quadnav.trajectory.quintic import quintic_average, quintic_c2, quintic_segments
from quadnav.trajectory.reference import Reference, Samples
from quadnav.trajectory.space import SafeSpace, trajectory_margins

__all__ = [
    "METHODS",
    "TIMINGS",
    "FeasibilityReport",
    "Limits",
    "Reference",
    "SafeSpace",
    "Samples",
    "Trajectory",
    "TrajectorySettings",
    "YawMode",
    "cubic_spline",
    "feasibility",
    "make_trajectory",
    "minimum_snap",
    "minimum_snap_qp",
    "ppoly_from_ascending",
    "quintic_average",
    "quintic_c2",
    "quintic_segments",
    "snap_cost",
    "trajectory_margins",
]
