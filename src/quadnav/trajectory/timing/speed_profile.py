"""The fastest speed along a curve within a speed and an acceleration limit.

A point moving along a curve at arc length ``s`` with speed ``sdot`` has the acceleration
``sddot T + kappa sdot^2 N`` (``T`` the unit tangent, ``N`` the unit normal, ``kappa`` the
curvature): its size is within ``a`` when ``sddot^2 + kappa^2 sdot^4 <= a^2``. So the
speed can never exceed ``sqrt(a / kappa)`` (the turn alone uses all of ``a``) nor ``v``,
and where it is below, the along-track acceleration is free within
``+-sqrt(a^2 - kappa^2 sdot^4)``.

:func:`fastest_speeds` is the time-optimal path parameterisation of this point (the
problem TOPP-RA solves, here with the exact bound on the size of the acceleration rather
than a polytope): on a grid of arc lengths, with ``x = sdot^2``, which changes by
``2 sddot ds`` over a step ``ds``, a backward pass lowers each ``x`` to what can still
brake to the next one and a forward pass to what can be reached from the previous one,
both starting from rest; the result is the largest speed at every point that both
passes allow (the bang-bang profile). Each step uses the curvature and speed at the point
it starts from. Optionally the acceleration may only grow from zero at each end as fast
as a given jerk allows, as a smooth trajectory that starts and stops at rest must.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError


def fastest_speeds(arc_length: ArrayLike, curvature: ArrayLike, v_max: float,
                   a_max: float, start_jerk: float | None = None) -> FloatArray:
    """The largest speeds (K,), m/s, at the arc lengths ``arc_length`` (K,) m, strictly
    increasing, of a curve with ``curvature`` (K,) 1/m there, from rest at the first
    point to rest at the last, with speed at most ``v_max`` m/s and acceleration (size
    of the vector) at most ``a_max`` m/s^2 (see the module docstring).

    With ``start_jerk`` (m/s^3), the acceleration grows from zero at each end no faster
    than that jerk allows: within ``(6 d j^2)^(1/3)`` at a distance ``d`` from the end (a
    move from rest at constant jerk ``j`` has ``a = j t`` and ``d = j t^3 / 6``)."""
    s = np.asarray(arc_length, dtype=np.float64)
    kappa = np.abs(np.asarray(curvature, dtype=np.float64))
    steps = np.diff(s)
    if s.ndim != 1 or len(s) < 2 or kappa.shape != s.shape or not np.all(steps > 0):
        raise QuadnavError("a speed profile needs (K,) strictly increasing arc lengths, "
                           "K >= 2, and (K,) curvatures")
    if not (v_max > 0 and a_max > 0 and math.isfinite(v_max) and math.isfinite(a_max)):
        raise QuadnavError(f"speed and acceleration limits must be > 0, got {v_max}, {a_max}")
    budget = np.full(s.shape, float(a_max))
    if start_jerk is not None:
        from_end = np.minimum(s - s[0], s[-1] - s)
        budget = np.minimum(budget, np.cbrt(6.0 * from_end * start_jerk**2))
    with np.errstate(divide="ignore"):
        ceiling = np.minimum(v_max * v_max, a_max / kappa)  # x = sdot^2 the turn allows
    ceiling[[0, -1]] = 0.0  # at rest at both ends
    x = ceiling.tolist()
    k, ds, a2 = kappa.tolist(), steps.tolist(), (budget * budget).tolist()
    for i in range(len(x) - 2, -1, -1):  # what can still brake to the next point
        x[i] = min(x[i], x[i + 1] + 2.0 * ds[i] * math.sqrt(
            max(a2[i] - (k[i + 1] * x[i + 1])**2, 0.0)))
    for i in range(len(x) - 1):  # what can be reached from the previous point
        x[i + 1] = min(x[i + 1], x[i] + 2.0 * ds[i] * math.sqrt(
            max(a2[i + 1] - (k[i] * x[i])**2, 0.0)))
    return np.sqrt(np.asarray(x))


def travel_times(arc_length: ArrayLike, speeds: ArrayLike) -> FloatArray:
    """Times (K,), s from the first point, at which a point moving with ``speeds`` (K,)
    m/s, varying linearly in time between grid points, passes ``arc_length`` (K,) m."""
    s = np.asarray(arc_length, dtype=np.float64)
    v = np.asarray(speeds, dtype=np.float64)
    mean = (v[:-1] + v[1:]) / 2.0
    if np.any(mean <= 0):
        raise QuadnavError("a speed profile stops between its ends")
    return np.concatenate([[0.0], np.cumsum(np.diff(s) / mean)])
