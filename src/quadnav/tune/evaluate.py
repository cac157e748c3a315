"""How well a set of gains flies a set: each :class:`~.sets.TuneItem` flown, its metrics,
and the one number a study minimises, :func:`objective`.

An item's cost is the natural log of its RMS tracking error over 1 cm, plus
:data:`OVERSHOOT_WEIGHT` per percent of a step's overshoot beyond
:data:`OVERSHOOT_ALLOWED` (a step's RMS error is mostly the jump itself, which a faster,
overshooting response shrinks: the penalty keeps the response a controls engineer would
accept), plus
:data:`SATURATION_WEIGHT` times the share of control steps at which the mixer saturated,
plus :data:`FAILURE_PENALTY` for a flight that did not reach the end of its reference
cleanly (a contact, leaving the world, diverging, missing the goal). The objective is the
mean cost over the items: without penalties, ``exp(objective)`` is the geometric mean RMS
error in centimetres, so every item counts by its ratio, the hover's millimetres as much as
a fast mission's centimetres. A failure costs as much as a 150 times larger error.

Flights run as jobs on an executor (:mod:`quadnav.batch.executor`): ``shared`` is a
:class:`Flights` (the vehicle, the base gains and the items), a job's item is
``(point, item index)``, and :func:`fly_item` returns the item's metrics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from quadnav.control.gains import Gains
from quadnav.sim.simulate import simulate
from quadnav.tracking import Tracking
from quadnav.tune.sets import TuneItem
from quadnav.tune.space import with_values
from quadnav.vehicle.params import VehicleParams

#: Cost of a failed flight, in units of log RMS error (a factor of e^5, about 150).
FAILURE_PENALTY = 5.0
#: Overshoot of a step that costs nothing, percent, and the cost per percent beyond it.
OVERSHOOT_ALLOWED = 5.0
OVERSHOOT_WEIGHT = 0.2
#: Cost per unit share of control steps with the mixer saturated.
SATURATION_WEIGHT = 2.0
#: The RMS error the log is taken against, m, and the least one counted.
ERROR_UNIT = 0.01
ERROR_FLOOR = 1e-5
#: Metrics kept per flight (:meth:`~quadnav.tracking.Tracking.metrics` keys).
KEPT = ("success", "ending", "rms_tracking_error_m", "max_tracking_error_m",
        "final_error_m", "mixer_saturation", "overshoot_percent", "settling_time_s")


@dataclass(frozen=True, eq=False)
class Flights:
    """What every evaluation job needs: the vehicle (the controller's model and, unless an
    item says otherwise, the plant), the gains that points change and the items."""

    vehicle: VehicleParams
    base: Gains
    items: tuple[TuneItem, ...]


def fly_with(item: TuneItem, vehicle: VehicleParams, gains: Gains) -> dict:
    """Fly ``item`` with ``gains``; returns its :data:`KEPT` metrics (None where a metric
    does not apply)."""
    flight = simulate(item.reference, item.plant or vehicle, gains, item.world,
                      item.settings, model=vehicle)
    metrics = Tracking(item.reference, item.world, flight, vehicle, gains,
                       item.settings).metrics()
    return {key: metrics.get(key) for key in KEPT}


def fly_item(flights: Flights, job: tuple[dict[str, float] | Gains, int]) -> dict:
    """An executor job: the item ``job[1]`` flown with the base gains changed by the point
    ``job[0]`` (knob name -> value), or with ``job[0]`` itself when it is a Gains."""
    point, index = job
    gains = point if isinstance(point, Gains) else with_values(flights.base, point)
    return fly_with(flights.items[index], flights.vehicle, gains)


def item_cost(metrics: dict) -> float:
    """One flight's cost (see the module docstring)."""
    error = max(float(metrics["rms_tracking_error_m"]), ERROR_FLOOR)
    cost = math.log(error / ERROR_UNIT)
    overshoot = float(metrics["overshoot_percent"] or 0.0)
    cost += OVERSHOOT_WEIGHT * max(overshoot - OVERSHOOT_ALLOWED, 0.0)
    cost += SATURATION_WEIGHT * float(metrics["mixer_saturation"])
    return cost + (0.0 if metrics["success"] else FAILURE_PENALTY)


def objective(flown: list[dict]) -> float:
    """The mean :func:`item_cost` of a set's flights."""
    return float(np.mean([item_cost(metrics) for metrics in flown]))


def scores(flown: list[dict]) -> dict:
    """A set's flights summed up for people: flights, successes, median and largest RMS
    tracking error (m), mean step overshoot (percent, None without steps), objective."""
    errors = [float(m["rms_tracking_error_m"]) for m in flown]
    overshoots = [float(m["overshoot_percent"]) for m in flown
                  if m["overshoot_percent"] is not None]
    return {"flights": len(flown), "successes": sum(bool(m["success"]) for m in flown),
            "median_rms_tracking_error_m": float(np.median(errors)),
            "max_rms_tracking_error_m": float(np.max(errors)),
            "mean_overshoot_percent": float(np.mean(overshoots)) if overshoots else None,
            "objective": objective(flown)}
