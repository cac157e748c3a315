"""Minimum-snap (and minimum-jerk) trajectories in closed form, and their cost.

:func:`minimum_derivative` minimises the integral of ``|d^r p / dt^r|^2`` over
piecewise polynomials of degree ``2r - 1`` (7 for snap, 5 for jerk) that pass every
waypoint at given times, start and end at rest (derivatives 1..r-1 zero) and have
continuous derivatives 1..r at the interior waypoints (up to snap for ``r = 4``, jerk for
``r = 3``). Without inequality constraints this is an equality-constrained QP whose
optimum solves one sparse linear (KKT) system; it is in fact ``C^(2r - 2)`` (the natural
conditions of the optimum make derivatives r+1..2r-2 continuous too). The matrices are
those of :mod:`quadnav.trajectory.polynomials.basis`;
:mod:`quadnav.trajectory.polynomials.minsnap_qp` adds corridors and limits
(:func:`~quadnav.trajectory.polynomials.minsnap_qp.minimum_snap_qp`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy import sparse
from scipy.sparse.linalg import splu

from quadnav.errors import QuadnavError
from quadnav.trajectory.model import Trajectory
from quadnav.trajectory.polynomials import basis
from quadnav.trajectory.polynomials.basis import METHOD_BY_ORDER

__all__ = ["METHOD_BY_ORDER", "minimum_derivative", "minimum_snap", "snap_cost"]


def minimum_derivative(waypoints: ArrayLike, times: ArrayLike, derivative: int = 4
                       ) -> Trajectory:
    """The trajectory through ``waypoints`` that minimises the integral of the squared
    ``derivative``-th time derivative (4: snap, 7th-order segments; 3: jerk, 5th-order).

    Args:
        waypoints: (N, 3) points, metres, N >= 2; waypoint ``i`` is passed at
            ``sum(times[:i])`` s.
        times: (N - 1,) segment durations, s, each > 0.
        derivative: 4 (minimum snap) or 3 (minimum jerk).

    Returns:
        A :class:`Trajectory`, method ``"minsnap"`` or ``"minjerk"``, at rest at both ends,
        ``C^r`` at the interior waypoints by construction (``C^(2r - 2)`` at the optimum).
        ``info["cost"]`` is the optimal cost summed over the axes, m^2/s^(2r - 1)
        (m^2/s^7 for snap).

    Raises:
        QuadnavError: fewer than 2 waypoints, times not one positive duration per segment,
            non-finite values, or an unsupported ``derivative``.
    """
    if derivative not in METHOD_BY_ORDER:
        raise QuadnavError(f"derivative must be one of {sorted(METHOD_BY_ORDER)} "
                           f"(jerk, snap), got {derivative}")
    points, durations = basis.check_waypoints_and_times(waypoints, times)
    r = derivative
    Q = basis.cost_matrix(durations, r)
    A, b = basis.equality_constraints(points, durations, r, continuity=r)
    kkt = sparse.bmat([[Q, A.T], [A, None]], format="csc")
    rhs = np.vstack([np.zeros((Q.shape[0], 3)), b])
    solution = splu(kkt).solve(rhs)
    coefficients = solution[:Q.shape[0]].reshape(len(durations), 2 * r, 3)
    info = {"cost": basis.trajectory_cost(coefficients, durations, r),
            "solver": "scipy.sparse.linalg.splu (KKT)", "continuity": r}
    return basis.trajectory_from_tau(coefficients, points, durations, METHOD_BY_ORDER[r], info)


def minimum_snap(waypoints: ArrayLike, times: ArrayLike) -> Trajectory:
    """:func:`minimum_derivative` with ``derivative=4``: the minimum-snap trajectory."""
    return minimum_derivative(waypoints, times, 4)


def snap_cost(trajectory: Trajectory, derivative: int = 4) -> float:
    """The integral over the whole trajectory of ``|d^r p / dt^r|^2`` (r = ``derivative``),
    summed over the axes, m^2/s^(2r - 1), integrated exactly from the polynomial
    coefficients: with ``a`` the ascending local-time coefficients of the derivative on a
    segment of ``T`` s, the integral is ``sum_kl a_k a_l T^(k+l+1) / (k+l+1)``."""
    if derivative < 0:
        raise QuadnavError(f"derivative must be >= 0, got {derivative}")
    ascending = trajectory.poly.derivative(derivative).c[::-1]  # (degree + 1, segments, 3)
    k = np.arange(len(ascending))
    power = k[:, None] + k[None, :] + 1
    hilbert = trajectory.segment_times[:, None, None] ** power / power  # (segments, K, K)
    return float(np.einsum("kia,ikl,lia->", ascending, hilbert, ascending))
