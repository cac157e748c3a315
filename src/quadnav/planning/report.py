"""Plain-data views of a planning result: the path as CSV, the statistics as JSON."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from quadnav.files import numbers_csv
from quadnav.limits import PLAN_ITERATIONS
from quadnav.planning.problem import PlanningProblem
from quadnav.planning.result import PlanResult, PlanStats
from quadnav.planning.settings import PlannerSettings


def path_csv(path: np.ndarray) -> str:
    """The path (N, 3) as CSV text with the header ``x,y,z`` (metres, full precision)."""
    return numbers_csv(("x", "y", "z"), path)


def _number(value: float | None) -> float | None:
    """JSON has no infinity: ``None`` stands for a missing or infinite value."""
    return None if value is None or not math.isfinite(value) else float(value)


def plan_summary(problem: PlanningProblem, result: PlanResult, settings: PlannerSettings,
                 raw_length: float | None = None) -> dict[str, Any]:
    """Everything about a query and its result except the tree, as JSON-ready data.

    Lengths in metres, times in seconds. ``raw_length`` is the length before
    post-processing (default: the result's own length).
    """
    world = problem.free_world
    stats = result.stats
    return {
        "map": problem.world.name,
        "planner": result.planner,
        "seed": result.seed,
        "solved": result.solved,
        "message": result.message,
        "margin": problem.margin,
        "start": problem.start.tolist(),
        "goal": problem.goal.tolist(),
        "search_start": problem.search_start.tolist(),
        "search_goal": problem.search_goal.tolist(),
        "length": _number(result.length),
        "raw_length": _number(result.length if raw_length is None else raw_length),
        "vertices": len(result.path),
        "settings": {
            "time_limit": settings.time_limit,
            "max_iterations": settings.max_iterations,
            "improve_iterations": settings.improve_iterations,
            "stall": None if settings.stall is None else {
                "fraction": settings.stall.fraction, "samples": settings.stall.samples},
            "stop_at_first": settings.stop_at_first,
            "step": settings.step_for(world),
            "goal_bias": settings.goal_bias,
            "goal_tolerance": settings.goal_tolerance_for(world),
            "rewire_factor": settings.rewire_factor,
            "informed": settings.informed,
        },
        "stats": {
            "iterations": stats.iterations,
            "stopped_by": stats.stopped_by,
            "stop_reason": stop_reason(stats, settings),
            "nodes": stats.nodes,
            "seconds": stats.seconds,
            "time_to_first": stats.time_to_first,
            "setup_seconds": stats.setup_seconds,
            "cost_history": stats.cost_history.tolist(),
            "post": [{"name": s.name, "length": s.length, "vertices": s.vertices,
                      "seconds": s.seconds} for s in stats.post],
        },
        "straight_line": float(np.linalg.norm(problem.goal - problem.start)),
    }


def stop_reason(stats: PlanStats, settings: PlannerSettings) -> str | None:
    """What ended a search under ``settings`` that went as ``stats`` said, in words (from
    its ``stopped_by``); None when the planner does not say."""
    stopped_by = stats.stopped_by
    capped = stats.iterations == (settings.max_iterations or PLAN_ITERATIONS.high)
    if stopped_by == "stall" and settings.stall is not None:
        return settings.stall.describe()
    if stopped_by == "improvement" and settings.stop_at_first:
        return "the first path (stop at first)"
    if stopped_by == "improvement" and settings.improve_iterations is not None and not capped:
        return f"the {settings.improve_iterations:,} samples allowed after the first path"
    if stopped_by in ("improvement", "iterations"):
        return f"the cap of {settings.max_iterations or PLAN_ITERATIONS.high:,} samples"
    if stopped_by == "time":
        return f"the time budget of {settings.time_limit:g} s"
    if stopped_by == "direct":
        return "the goal is in sight of the start: joined directly, no search"
    return None
