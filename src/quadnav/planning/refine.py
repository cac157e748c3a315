"""Post-process a planner's path: shortcuts, then (optionally) smoothing.

Only the search part of the path — from :attr:`PlanningProblem.search_start` to
:attr:`PlanningProblem.search_goal`, in the inflated world — is changed; the short legs
out of the safety margin (see :meth:`PlanningProblem.full_path`) are kept as they are.
"""

from __future__ import annotations

import dataclasses
import time

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.planning.problem import PlanningProblem
from quadnav.planning.result import PlanResult, PostStep, path_length
from quadnav.planning.shortcut import shortcut_path
from quadnav.planning.smoothing import smooth_path


def refine(problem: PlanningProblem, result: PlanResult, seed: int | None = None,
           smooth: bool = True, attempts: int | None = None,
           **smoothing: float | int | None) -> PlanResult:
    """``result`` with a shorter (and smoother) path, the steps recorded in its stats.

    Args:
        problem: the query ``result`` answers.
        result: a planner's result; returned unchanged when not solved.
        seed: seed of the random shortcuts; ``None``: ``result.seed``.
        smooth: whether to smooth after shortcutting.
        attempts: random shortcuts tried (see :func:`shortcut_path`).
        **smoothing: options of :func:`smooth_path` (``weight_data``, ``weight_smooth``,
            ``tolerance``, ``max_spacing``, ``max_sweeps``).

    Returns:
        A copy of ``result`` whose path runs from exactly ``problem.start`` to exactly
        ``problem.goal`` and whose ``stats.post`` ends with a ``"shortcut"`` and (when
        ``smooth``) a ``"smooth"`` :class:`PostStep`, each giving the length (metres)
        and vertex count of the whole path, legs included, after that step.
    """
    if smoothing and not smooth:
        raise QuadnavError(f"smoothing options {', '.join(smoothing)} given with smooth=False")
    if not result.solved:
        return result
    search = problem.search_part(result.path)
    started = time.perf_counter()
    search = shortcut_path(problem.free_world, search,
                           seed=result.seed if seed is None else seed, attempts=attempts)
    steps = [_post_step("shortcut", problem.full_path(search), started)]
    if smooth:
        started = time.perf_counter()
        search = smooth_path(problem.free_world, search, **smoothing)
        steps.append(_post_step("smooth", problem.full_path(search), started))
    stats = dataclasses.replace(result.stats, post=(*result.stats.post, *steps))
    return result.replace(path=problem.full_path(search), stats=stats)


def _post_step(name: str, path: FloatArray, started: float) -> PostStep:
    """The :class:`PostStep` of a step begun at ``perf_counter() == started`` that left
    the full path (N, 3)."""
    return PostStep(name, path_length(path), len(path), time.perf_counter() - started)
