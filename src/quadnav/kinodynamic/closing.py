"""The closing stop of a quadrotor plan: from a moving state to rest exactly at the goal.

From position ``p`` and velocity ``v`` (m, m/s), two constant accelerations held for the
same time ``tau`` each end at rest at ``g``::

    a1 = (g - p - 3/2 v tau) / tau^2        then        a2 = (p - g + v tau / 2) / tau^2

(the first takes the velocity to ``(g - p) / tau - v / 2``, the second from there to 0,
covering exactly the rest of the way). Both shrink as ``tau`` grows, so some ``tau`` is
always within the limits; :func:`closing_candidates` lists, on a geometric grid of
``tau``, those whose accelerations the model can fly (at most
:data:`CLOSING_ACCELERATION`) and that stay within its speed limit, shortest first. The
planner checks them against the map like every other motion and keeps the shortest free
one (:func:`~quadnav.kinodynamic.quadrotor.plan_quadrotor`).
"""

from __future__ import annotations

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.kinodynamic.pointmass import SampledQuadrotor

#: Largest acceleration of a closing stop, m/s^2 (the default model brakes at up to
#: 3.6 m/s^2 horizontally, g tan 0.35 rad; a gentler stop is tracked more closely).
CLOSING_ACCELERATION = 3.0
#: The grid of ``tau``, s: from :data:`SHORTEST_HALF` growing by :data:`HALF_GROWTH` up to
#: :data:`LONGEST_HALF`.
SHORTEST_HALF = 0.05
HALF_GROWTH = 1.1
LONGEST_HALF = 5.0


def closing_accelerations(state: FloatArray, goal: FloatArray, halves: FloatArray
                          ) -> tuple[FloatArray, FloatArray]:
    """The two accelerations (n, 3) each, m/s^2, that take ``state`` (6,) (position m,
    velocity m/s) to rest at ``goal`` (3,) m in two pieces of ``halves`` (n,) s each."""
    tau = np.asarray(halves, dtype=np.float64)[:, None]
    offset, velocity = np.asarray(goal) - state[:3], state[3:]
    return (offset - 1.5 * velocity * tau) / tau**2, (0.5 * velocity * tau - offset) / tau**2


def closing_candidates(model: SampledQuadrotor, state: FloatArray, goal: FloatArray
                       ) -> tuple[FloatArray, FloatArray]:
    """The closing stops from ``state`` (6,) to rest at ``goal`` (3,) that ``model`` can
    fly, shortest first: ``(halves (n,) s, controls (n, 2, 3))``, the controls of the two
    accelerations (:func:`closing_accelerations`); each acceleration at most
    :data:`CLOSING_ACCELERATION` and within the model's limits, the speed between them
    within its speed limit (the speed along a constant acceleration is convex in time, so
    the ends bound it: ``state``'s speed, the middle one, and 0). n may be 0."""
    count = int(np.floor(np.log(LONGEST_HALF / SHORTEST_HALF) / np.log(HALF_GROWTH))) + 1
    halves = SHORTEST_HALF * HALF_GROWTH ** np.arange(count)
    first, second = closing_accelerations(state, goal, halves)
    middle = state[3:] + first * halves[:, None]
    keep = np.maximum(np.linalg.norm(first, axis=1),
                      np.linalg.norm(second, axis=1)) <= CLOSING_ACCELERATION
    if model.speed_limit is not None:
        keep &= np.einsum("ij,ij->i", middle, middle) <= model.speed_limit**2
    rows, controls = [], []
    for row in np.flatnonzero(keep):
        pair = [model.control_for(first[row]), model.control_for(second[row])]
        if pair[0] is not None and pair[1] is not None:
            rows.append(row)
            controls.append(pair)
    return halves[np.array(rows, dtype=np.int64)], np.array(controls).reshape(-1, 2, 3)
