"""Shared matrices of piecewise polynomials in normalised time, for minimum-derivative
trajectories (:mod:`quadnav.trajectory.polynomials.minsnap`,
:mod:`quadnav.trajectory.polynomials.minsnap_qp`).

Segment ``i`` of duration ``T_i`` s runs from waypoint ``i`` to waypoint ``i + 1``; per
axis it is ``p(tau) = sum_k c_k tau^k`` with ``2r`` coefficients (degree ``2r - 1``: 7 for
snap, ``r = 4``; 5 for jerk, ``r = 3``) in the normalised local time
``tau = (t - t_i) / T_i`` in [0, 1], which keeps every coefficient on the scale of the
positions. Time derivatives are ``d^j p / dt^j = T_i^-j d^j p / dtau^j``.

The unknowns of one axis are the ``2r * segments`` coefficients ``c``, segment by segment
(index ``i * 2r + k``); the three axes share every matrix and differ only in the
right-hand sides, which are (rows, 3) arrays.
"""

from __future__ import annotations

from math import factorial

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import sparse

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.trajectory.model import Trajectory, ppoly_from_ascending

#: Trajectory method names by the order ``r`` of the minimised derivative.
METHOD_BY_ORDER = {3: "minjerk", 4: "minsnap"}


def check_waypoints_and_times(waypoints: ArrayLike, times: ArrayLike
                              ) -> tuple[FloatArray, FloatArray]:
    """Validated float64 copies of ``waypoints`` (N, 3) m, N >= 2, and segment durations
    ``times`` (N - 1,) s, each finite and > 0; :class:`QuadnavError` otherwise."""
    try:
        points = np.array(waypoints, dtype=np.float64)
        durations = np.array(times, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise QuadnavError(f"waypoints and times must be numbers: {error}") from None
    if points.ndim != 2 or points.shape[1] != 3 or len(points) < 2:
        raise QuadnavError(f"waypoints must have shape (N, 3) with N >= 2, got {points.shape}")
    if not np.all(np.isfinite(points)):
        row = int(np.argwhere(~np.isfinite(points))[0, 0])
        raise QuadnavError(f"waypoint {row} is {points[row].tolist()}; expected finite numbers")
    if durations.shape != (len(points) - 1,):
        raise QuadnavError(f"times must have shape ({len(points) - 1},), one duration per "
                           f"segment between {len(points)} waypoints, got {durations.shape}")
    bad = ~(np.isfinite(durations) & (durations > 0))
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise QuadnavError(f"segment time {i} is {durations[i]} s; expected a finite "
                           "duration > 0 s")
    return points, durations


def derivative_rows(coefficients: int, order: int, tau: ArrayLike) -> FloatArray:
    """(len(tau), coefficients) matrix ``M`` with ``M @ c`` = the ``order``-th derivative
    with respect to ``tau`` of ``sum_k c_k tau^k`` at each ``tau``."""
    taus = np.atleast_1d(np.asarray(tau, dtype=np.float64))
    k = np.arange(coefficients)
    falling = np.array([factorial(n) // factorial(n - order) if n >= order else 0 for n in k],
                       dtype=np.float64)
    return falling * taus[:, None] ** np.maximum(k - order, 0)


def tau_cost_matrix(r: int) -> FloatArray:
    """(2r, 2r) matrix ``H`` with ``c @ H @ c`` = the integral over tau in [0, 1] of
    ``(d^r p / dtau^r)^2``; the time integral of ``(d^r p / dt^r)^2`` over a segment of
    ``T`` s is that times ``T^(1 - 2r)``."""
    k = np.arange(2 * r)
    falling = np.array([factorial(n) / factorial(n - r) if n >= r else 0.0 for n in k])
    power = np.maximum(k[:, None] + k[None, :] - 2 * r + 1, 1)
    return np.outer(falling, falling) / power


def cost_matrix(times: FloatArray, r: int) -> sparse.csc_matrix:
    """Block-diagonal (2r * segments) square matrix ``Q`` with ``c @ Q @ c`` = the sum over
    segments of the integral of ``(d^r p / dt^r)^2`` times ``median(times)^(2r - 1)``, a
    positive factor (the optimum does not depend on it) that brings the entries near 1."""
    weights = (times / np.median(times)) ** (1 - 2 * r)
    return sparse.kron(sparse.diags(weights), tau_cost_matrix(r), format="csc")


def trajectory_cost(coefficients: FloatArray, times: FloatArray, r: int) -> float:
    """Sum over segments and axes of the integral of ``(d^r p / dt^r)^2``, in
    m^2 / s^(2r - 1), from tau-coefficients (segments, 2r, 3)."""
    per_segment = np.einsum("ika,kl,ila->i", coefficients, tau_cost_matrix(r), coefficients)
    return float(np.sum(per_segment * times ** (1 - 2 * r)))


def equality_constraints(waypoints: FloatArray, times: FloatArray, r: int, continuity: int
                         ) -> tuple[sparse.csr_matrix, FloatArray]:
    """``A`` (rows, 2r * segments) and ``b`` (rows, 3) of the constraints ``A @ c = b``:

    * the waypoint positions at both ends of every segment;
    * continuity of derivatives 1..``continuity`` at every interior waypoint; each row
      ``T_i^-j D_j(1) c_i - T_{i+1}^-j D_j(0) c_{i+1} = 0`` is multiplied by
      ``min(T_i, T_{i+1})^j`` so that its entries are at most ``(2r - 1)! / (2r - 1 - j)!``;
    * zero derivatives 1..r-1 (velocity, acceleration, jerk for r = 4) at both ends.
    """
    segments, n = len(times), 2 * r
    rows, cols, vals = [], [], []

    def add(block: FloatArray, segment: NDArray[np.int_], first_row: int) -> None:
        """``block`` (len(segment), n) on the coefficients of each ``segment``, one row
        each from ``first_row`` on."""
        rows.append(np.repeat(first_row + np.arange(len(segment)), n))
        cols.append((segment[:, None] * n + np.arange(n)).ravel())
        vals.append(block.ravel())

    every = np.arange(segments)
    add(np.repeat(derivative_rows(n, 0, 0.0), segments, axis=0), every, 0)
    add(np.repeat(derivative_rows(n, 0, 1.0), segments, axis=0), every, segments)
    count = 2 * segments
    left, right = every[:-1], every[1:]
    for j in range(1, continuity + 1):
        scale = np.minimum(times[left], times[right]) ** j
        add(derivative_rows(n, j, 1.0) * (scale / times[left] ** j)[:, None], left, count)
        add(-derivative_rows(n, j, 0.0) * (scale / times[right] ** j)[:, None], right, count)
        count += segments - 1
    for j in range(1, r):
        add(derivative_rows(n, j, 0.0), every[:1], count)
        add(derivative_rows(n, j, 1.0), every[-1:], count + 1)
        count += 2
    A = sparse.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                          shape=(count, n * segments))
    A.eliminate_zeros()
    b = np.zeros((count, 3))
    b[:segments], b[segments:2 * segments] = waypoints[:-1], waypoints[1:]
    return A, b


def trajectory_from_tau(coefficients: FloatArray, waypoints: FloatArray, times: FloatArray,
                        method: str, info: dict) -> Trajectory:
    """A :class:`Trajectory` from tau-coefficients (segments, 2r, 3): each ``c_k`` becomes
    the local-time coefficient ``c_k / T_i^k``."""
    powers = times[:, None] ** -np.arange(coefficients.shape[1])
    breaks = np.concatenate([[0.0], np.cumsum(times)])
    return Trajectory(ppoly_from_ascending(coefficients * powers[:, :, None], breaks),
                      waypoints, method, info=info)
