"""How a flight answered a step of its position reference: :func:`step_response`.

The response is measured along the step: ``y = (p - start) . u / size``, with ``u`` the
step's direction and ``size`` its length, so it runs from 0 before the step to 1 at the
target. From the step time on:

* overshoot: how far ``y`` went past 1, as a fraction of the step;
* rise time: from ``y`` first reaching 10 % to first reaching 90 %;
* settling time: from the step until ``y`` enters the band ``1 +- band`` (2 %) for good
  (None if it is outside at the last sample);
* steady-state error: the distance from the mean position over the last
  :data:`STEADY_SHARE` of the time after the step (at least :data:`STEADY_LEAST` s) to the
  target, m.

The measures are at the recorded samples, so record at the control rate
(:attr:`~quadnav.sim.settings.SimSettings.record_rate`) for millisecond times.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray

#: Half-width of the settling band, as a fraction of the step.
SETTLING_BAND = 0.02
#: Levels between which the rise time is measured, as fractions of the step.
RISE_LEVELS = (0.1, 0.9)
#: Share of the time after the step, and the least time, s, averaged for the steady state.
STEADY_SHARE = 0.1
STEADY_LEAST = 0.5


@dataclass(frozen=True)
class StepResponse:
    """Figures of merit of a step response (see the module docstring).

    Attributes:
        overshoot: largest excursion past the target along the step, as a fraction of the
            step (0 if none).
        rise_time: s from 10 % to 90 % of the step, or None if 90 % was never reached.
        settling_time: s from the step until within the band for good, or None if it is
            outside at the end.
        steady_state_error: distance of the final mean position from the target, m.
    """

    overshoot: float
    rise_time: float | None
    settling_time: float | None
    steady_state_error: float


def step_response(t: ArrayLike, position: ArrayLike, start: ArrayLike, target: ArrayLike,
                  at: float, band: float = SETTLING_BAND) -> StepResponse:
    """The response of the flown ``position`` (N, 3) m at times ``t`` (N,) s to a step
    from ``start`` (3,) m to ``target`` (3,) m at ``at`` s; ``band`` is the settling band
    as a fraction of the step. ValueError if no sample is at or after the step."""
    times = np.asarray(t, dtype=np.float64)
    points = np.asarray(position, dtype=np.float64)
    start, target = np.asarray(start, dtype=np.float64), np.asarray(target, dtype=np.float64)
    after = times >= at
    if not np.any(after):
        raise ValueError(f"no sample at or after the step at {at:g} s")
    times, points = times[after], points[after]
    jump = target - start
    size = float(np.linalg.norm(jump))
    progress = (points - start) @ jump / size**2
    return StepResponse(
        overshoot=max(float(progress.max()) - 1.0, 0.0),
        rise_time=_rise_time(times, progress),
        settling_time=_settling_time(times, progress, at, band),
        steady_state_error=_steady_state_error(times, points, target, at))


def _first(times: FloatArray, reached: np.ndarray) -> float | None:
    """The first time at which ``reached`` holds, or None."""
    found = np.flatnonzero(reached)
    return float(times[found[0]]) if len(found) else None


def _rise_time(times: FloatArray, progress: FloatArray) -> float | None:
    low, high = (_first(times, progress >= level) for level in RISE_LEVELS)
    return None if low is None or high is None else high - low


def _settling_time(times: FloatArray, progress: FloatArray, at: float, band: float
                   ) -> float | None:
    outside = np.flatnonzero(np.abs(progress - 1.0) > band)
    if len(outside) == 0:
        return 0.0
    if outside[-1] == len(times) - 1:
        return None
    return float(times[outside[-1] + 1]) - at


def _steady_state_error(times: FloatArray, points: FloatArray, target: FloatArray,
                        at: float) -> float:
    window = max(STEADY_SHARE * (times[-1] - at), STEADY_LEAST)
    final = points[times >= times[-1] - window].mean(axis=0)
    return float(np.linalg.norm(final - target))
