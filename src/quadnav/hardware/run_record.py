"""A Tello flight as a run folder (:mod:`quadnav.runs`), so that ``report``, ``view``,
``animate`` and ``blender`` show it as they show a simulated ``fly`` run.

What the folder holds for a Tello flight:

* ``map.json``, ``tree.csv``, ``path.csv``, ``trajectory.csv`` — the map (with the start,
  goal and margin flown), the planner's tree, the planned route with the takeoff and
  landing columns (floor under the start, takeoff point, route, floor under the goal) and
  the planned trajectory, as a ``fly`` run writes them;
* ``flight.csv`` — the flown track: the dead-reckoned position at each state packet (and
  the mission pad's where one was seen), with its time in drone seconds from the start of
  the log. The velocity is the track's finite difference; the attitude is level, facing
  the takeoff heading (``go`` and ``rc`` moves never turn the drone, and a state packet's
  whole-degree pitch and roll say little); the motor columns are empty (NaN: a Tello does
  not report them); the reference columns hold the nearest point of the planned route, so
  the tracking error is the distance from the route (a ``go`` flight has no timed
  reference to compare with);
* ``metrics.json`` — ``success`` (landed at the goal), ``ending`` (the bridge's outcome),
  the tracking error against the route, the final horizontal error at the landing, the
  least exact clearance of the track to the real blocks, walls and ceiling (the floor,
  where the drone stands before takeoff and after landing, does not count; beside
  ``margin_m``, the margin the geofence kept), and ``source: "tello"``;
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
from quadnav.hardware.bridge import BridgeSettings, Outcome, Status
from quadnav.hardware.flight_plan import FlightPlan
from quadnav.planning.result import nearest_on_polyline, path_length
from quadnav.runs import FlightTable, RunContent
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


def tello_metrics(plan: FlightPlan, table: FlightTable, outcome: Outcome) -> dict:
    """metrics.json of a Tello flight (see the module docstring)."""
    flown = len(table.t) > 0
    error = np.linalg.norm(table.position - table.reference, axis=1)
    world = plan.fence.world
    landed = outcome.status is Status.LANDED
    final = (float(np.linalg.norm(table.position[-1, :2] - plan.problem.goal[:2]))
             if flown else None)
    # The floor, where it takes off and lands, is not an obstacle: lowered out of the way.
    boundary = world.boundary.copy()
    boundary[2] -= FLOOR_DROP
    walls = world.replace(boundary=boundary)
    clearance = float(walls.clearances(table.position).min()) if flown else None
    return {
        "source": SOURCE,
        "map": world.name,
        "start": plan.problem.start.tolist(),
        "goal": plan.problem.goal.tolist(),
        "margin_m": plan.fence.margin,
        "planner": plan.result.planner,
        "seed": plan.result.seed,
        "vehicle": "tello",
        "success": landed,
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
        "final_error_m": final,
        "min_clearance_m": clearance,
        "state_packets": len(table.t),
    }


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


def tello_run_content(plan: FlightPlan, settings: BridgeSettings, outcome: Outcome,
                      track: ArrayLike, host: str | None) -> RunContent:
    """The run folder content of a Tello flight (a dry run: the plan alone, no flight)."""
    table = flown_table(plan, track)
    world = plan.fence.world.replace(start=plan.problem.start, goal=plan.problem.goal,
                                     margin=plan.fence.margin)
    flown = len(table.t) > 0
    tree = plan.result.tree_nodes, plan.result.tree_parents
    return RunContent(world, tello_metrics(plan, table, outcome),
                      tello_parameters(plan, settings, host),
                      tree if len(tree[0]) else None, planned_route(plan),
                      plan.trajectory if flown else None, table if flown else None)
