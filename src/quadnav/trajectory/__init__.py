"""Trajectory stage: smooth, timed references through waypoints (a planner's path).

* :func:`make_trajectory` with :class:`TrajectorySettings` — the stage's entry point
  (:mod:`.generate`); the stage ends with a trajectory the vehicle can fly
  (:mod:`.envelope`).
* :class:`SafeSpace` — the map and margin a trajectory keeps outside the legs out of the
  margin; :func:`trajectory_margins` measures the margin kept, exactly.
* :class:`Trajectory` — a piecewise polynomial per axis with a yaw reference.
* :class:`Reference` — what the simulation flies: a Trajectory or anything else with a
  position, velocity, acceleration and yaw over time (built-in shapes in
  :mod:`.references.builtin`, samples read from a file in :mod:`.references.sampled`, a
  plain-Python class in rotorpy's shape, ``update(t) -> flat outputs``, sampled in
  :mod:`.references.plain`).
* Generators ``(waypoints (N, 3), segment times (N - 1,)) -> Trajectory``:
  :func:`minimum_snap`, :func:`minimum_snap_qp`, :func:`quintic_segments`,
  :func:`quintic_c2`, :func:`quintic_average`, :func:`cubic_spline`.
* :func:`feasibility` — peaks against a vehicle's :class:`Limits`.

The rooms: :mod:`.polynomials` (the generators' piecewise polynomials), :mod:`.timing`
(segment times), :mod:`.clearance` (collision checks, corridors, the safe space and its
exact margins) and :mod:`.references` (the Reference contract and the references not
made from waypoints: built-in shapes, plain-Python classes, files, and a reference
written as a file).
"""

from quadnav.trajectory.clearance.space import SafeSpace, trajectory_margins
from quadnav.trajectory.feasibility import FeasibilityReport, Limits, feasibility
from quadnav.trajectory.generate import (
    METHODS,
    TIMINGS,
    TrajectorySettings,
    make_trajectory,
)
from quadnav.trajectory.model import Trajectory, YawMode, ppoly_from_ascending
from quadnav.trajectory.polynomials.cubic import cubic_spline
from quadnav.trajectory.polynomials.minsnap import minimum_snap, snap_cost
from quadnav.trajectory.polynomials.minsnap_qp import minimum_snap_qp
from quadnav.trajectory.polynomials.quintic import quintic_average, quintic_c2, quintic_segments
from quadnav.trajectory.references.contract import Reference, Samples

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
