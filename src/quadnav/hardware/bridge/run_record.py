"""A Tello flight as a run folder (:mod:`quadnav.runs`), so that ``report``, ``view``,
``animate`` and ``blender`` show it as they show a simulated ``fly`` run.

What the folder holds for a Tello flight:

* ``map.json``, ``tree.csv``, ``path.csv``, ``trajectory.csv`` — the map (with the start,
  goal and margin flown), the planner's tree, the planned route with the takeoff and
  landing columns (floor under the start, takeoff point, route, floor under the goal) and
  the planned trajectory, as a ``fly`` run writes them;
* ``flight.csv`` — the flown track: the dead-reckoned position at each state packet (and
  the mission pad's where one was seen), with its time in drone seconds from the start of
  the estimate (as the log's). The velocity is the track's finite difference; the
  attitude is level, facing the takeoff heading (``go`` and ``rc`` moves never turn the
  drone, and a state packet's whole-degree pitch and roll say little); the motor columns
  are empty (NaN: a Tello does not report them); the reference columns hold the nearest
  point of the planned route, so the tracking error is the distance from the route (a
  ``go`` flight has no timed reference to compare with);
* ``metrics.json`` — ``success`` (landed at the goal), ``ending`` (the bridge's outcome),
  the tracking error against the route, ``landing_m`` and ``landing_sigma_m`` (the
  dead-reckoned landing place and its 1-sigma horizontal uncertainty: the place the last
  line printed), ``final_error_m`` (that place's horizontal distance from the floor under the
  goal) and ``goal_tolerance_m`` (the most it may be for a success), the least exact
  clearance of the track to the real blocks, walls and ceiling (the floor, where the
  drone stands before takeoff and after landing, does not count; beside ``margin_m``, the
  margin the geofence kept), and ``source: "tello"``. With a true track (flown against
  the emulator), also ``true_landing_m`` (where the drone truly landed),
  ``true_final_error_m`` (its distance from the goal) and the drift of the estimate from
  the truth, horizontally: ``landing_drift_m`` at the landing, ``rms_drift_m`` and
  ``max_drift_m`` over the state packets;
* ``truth.csv`` — the true track (:mod:`quadnav.hardware.truth`), in flight.csv's time,
  when it was known;
* ``parameters.json`` — the mode, host, speed, margin, heading and time scale flown, and
  the planner's settings.

The log (``tello_log.jsonl``: every command, reply and state packet) and
``tello_track.png`` stay beside them.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.config import as_plain
from quadnav.hardware.bridge.dead_reckoning import Estimate
from quadnav.hardware.bridge.flight import (
    LANDING_TOLERANCE,
    BridgeSettings,
    Flown,
    Outcome,
    Status,
    landing_error,
)
from quadnav.hardware.bridge.flight_plan import FlightPlan
from quadnav.planning.result import nearest_on_polyline, path_length
from quadnav.runs import FlightTable, RunContent, drift
from quadnav.vehicle import quaternion
from quadnav.vehicle.params import load_params

#: What metrics.json names as the source of a Tello run.
SOURCE = "tello"
#: How far the floor is lowered for the clearance of a flown track, m: more than any
#: dead-reckoned height below it, so the floor it stands on is never the nearest face.
FLOOR_DROP = 10.0


def planned_route(plan: FlightPlan) -> FloatArray:
    """(N, 3) what the drone was planned to fly, m: up from the floor under the start to
    the takeoff point, the route, down to the floor under its end."""
    return plan.between_columns(plan.route.points)


def flown_table(plan: FlightPlan, track: ArrayLike) -> FlightTable:
    """The flight table of a dead-reckoned ``track`` (N, 4: drone s, map x, y, z in m);
    see the module docstring for each column."""
    rows = np.asarray(track, dtype=np.float64).reshape(-1, 4)
    t, position = rows[:, 0], rows[:, 1:4]
    velocity = (np.gradient(position, t, axis=0) if len(t) >= 2 and np.all(np.diff(t) > 0)
                else np.zeros_like(position))
    attitude = np.tile(quaternion.from_yaw(plan.frame.yaw), (len(t), 1))
    return FlightTable(t, position, velocity, attitude, np.full((len(t), 4), np.nan),
                       nearest_on_polyline(position, planned_route(plan)))


def truth_metrics(plan: FlightPlan, table: FlightTable, truth: FloatArray,
                  landing: Estimate | None) -> dict:
    """The metrics of a flight whose true track ``truth`` (K, 4: t s, x, y, z m) is known:
    where it truly landed (the track's end; None without a confirmed ``landing``), how far
    that is from the goal, and the drift of the estimate from it, horizontally: at the
    landing, and its RMS and largest over the rows of ``table``."""
    drifts = drift(table, truth)
    end = truth[-1, 1:4]
    return {
        "true_landing_m": None if landing is None else end.tolist(),
        "true_final_error_m": (None if landing is None else float(
            np.linalg.norm(end[:2] - plan.landing_ground[:2]))),
        "landing_drift_m": (None if landing is None
                            else float(np.linalg.norm(landing.point[:2] - end[:2]))),
        "rms_drift_m": float(np.sqrt(np.mean(drifts ** 2))),
        "max_drift_m": float(drifts.max()),
    }


def tello_metrics(plan: FlightPlan, table: FlightTable, outcome: Outcome,
                  truth: FloatArray | None = None) -> dict:
    """metrics.json of a Tello flight (see the module docstring), with
    :func:`truth_metrics` when the true track ``truth`` is known."""
    flown = len(table.t) > 0
    error = np.linalg.norm(table.position - table.reference, axis=1)
    world = plan.fence.world
    landing = outcome.landing
    final = None if landing is None else landing_error(plan, landing)
    # The floor, where it takes off and lands, is not an obstacle: lowered out of the way.
    boundary = world.boundary.copy()
    boundary[2] -= FLOOR_DROP
    walls = world.replace(boundary=boundary)
    clearance = float(walls.clearances(table.position).min()) if flown else None
    metrics = {
        "source": SOURCE,
        "map": world.name,
        "start": plan.problem.start.tolist(),
        "goal": plan.problem.goal.tolist(),
        "margin_m": plan.fence.margin,
        "planner": plan.result.planner,
        "seed": plan.result.seed,
        "vehicle": "tello",
        "success": outcome.status is Status.LANDED,
        "path_found": True,
        "ending": outcome.status.value,
        "message": outcome.message,
        "collision": clearance is not None and clearance <= 0.0,
        "contact_time_s": float(table.t[-1]) if flown else 0.0,
        "flight_time_s": float(table.t[-1] - table.t[0]) if flown else 0.0,
        "path_length_m": path_length(plan.route.points),
        "speed_m_s": plan.speed,
        "rms_tracking_error_m": float(np.sqrt(np.mean(error ** 2))) if flown else None,
        "max_tracking_error_m": float(error.max()) if flown else None,
        "landing_m": None if landing is None else landing.point.tolist(),
        "landing_sigma_m": None if landing is None else landing.sigma,
        "final_error_m": final,
        "goal_tolerance_m": LANDING_TOLERANCE,
        "min_clearance_m": clearance,
        "state_packets": len(table.t),
    }
    if truth is not None and flown:
        metrics |= truth_metrics(plan, table, truth, landing)
    return metrics


def tello_parameters(plan: FlightPlan, settings: BridgeSettings, host: str | None) -> dict:
    """parameters.json of a Tello flight: how it was flown and planned."""
    return {
        "source": SOURCE,
        "mode": settings.mode,
        "host": host,
        "dry_run": host is None,
        "speed_m_s": plan.speed,
        "margin_m": plan.fence.margin,
        "yaw_rad": plan.frame.yaw,
        "time_scale": settings.time_scale,
        "min_battery_percent": settings.min_battery,
        "planner": plan.result.planner,
        "seed": plan.result.seed,
        "vehicle": as_plain(load_params("tello")),
    }


def tello_run_content(plan: FlightPlan, settings: BridgeSettings, flown: Flown,
                      host: str | None) -> RunContent:
    """The run folder content of a Tello flight (a dry run: the plan alone, no flight)."""
    table = flown_table(plan, flown.track)
    world = plan.fence.world.replace(start=plan.problem.start, goal=plan.problem.goal,
                                     margin=plan.fence.margin)
    has_flight = len(table.t) > 0
    tree = plan.result.tree_nodes, plan.result.tree_parents
    return RunContent(world, tello_metrics(plan, table, flown.outcome, flown.truth),
                      tello_parameters(plan, settings, host),
                      tree if len(tree[0]) else None, planned_route(plan),
                      plan.trajectory if has_flight else None,
                      table if has_flight else None, flown.truth if has_flight else None)
