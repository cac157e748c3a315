"""Waypoints to the Tello SDK's relative ``go x y z speed`` moves, within the SDK's limits.

A ``go`` move is a whole-centimetre step in the takeoff frame (see
:mod:`quadnav.hardware.bridge.frames`) and a speed in cm/s. The SDK refuses a move with any
component outside +-:data:`GO_MAX_CM`, a speed outside :data:`SPEED_RANGE`, or all three
components within +-:data:`GO_MIN_CM` (a move that short is refused, so it is counted
as too short here). :func:`go_moves` therefore

* **splits** a long step into equal pieces of at most 500 cm per axis;
* **merges** a step that is too short into the next one, flying straight from the
  current point to the waypoint after, when that straight line is allowed;
* otherwise (a short step that cannot be merged, e.g. the last one) makes a
  **detour**: two allowed moves through a point :data:`DETOUR_CM` off the target.

Every move is checked with the caller's ``allowed(start_cm, end_cm, segments)`` predicate
(the geofence, or on a leg the leg's room), which is told which waypoint segments the move
stands in for; the moves end exactly on the last waypoint.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from itertools import pairwise

import numpy as np
from numpy.typing import ArrayLike

from quadnav.errors import QuadnavError
from quadnav.hardware.bridge.frames import IntArray

#: Largest component of a ``go`` move, cm.
GO_MAX_CM = 500
#: A ``go`` move needs at least one component beyond +-GO_MIN_CM, cm.
GO_MIN_CM = 20
#: Slowest and fastest ``go`` speed, cm/s.
SPEED_RANGE = (10, 100)
#: How far off the target a detour's middle point lies, cm (> 2 GO_MIN_CM, so both of
#: its moves are long enough).
DETOUR_CM = 45
#: Detour directions tried in order (takeoff frame): up first, then down, then level.
_DETOURS = np.array([[0, 0, 1], [0, 0, -1], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]])

#: ``allowed(start, end, segments)``: whether the straight move between two takeoff-frame
#: points in whole centimetres, each (3,), may be flown in place of the waypoint segments
#: ``segments`` (segment ``k`` runs from waypoint ``k`` to ``k + 1``).
Allowed = Callable[[IntArray, IntArray, range], bool]
#: ``rule(segments)``: what a move in place of ``segments`` must stay in, in words.
Rule = Callable[[range], str]


def _the_fence(segments: range) -> str:
    """The default :data:`Rule`: the geofence everywhere."""
    return "the geofence"


class MoveError(QuadnavError):
    """Waypoints that cannot be turned into allowed ``go`` moves."""


@dataclass(frozen=True)
class Move:
    """One ``go x y z speed`` command: a takeoff-frame step in cm at ``speed`` cm/s."""

    x: int
    y: int
    z: int
    speed: int

    def __post_init__(self) -> None:
        step = self.step
        if not (is_long_enough(step) and np.all(np.abs(step) <= GO_MAX_CM)
                and SPEED_RANGE[0] <= self.speed <= SPEED_RANGE[1]):
            raise MoveError(f"'{self.command}' is outside the SDK's limits (each axis "
                            f"-{GO_MAX_CM}..{GO_MAX_CM} cm, not all within +-{GO_MIN_CM} "
                            f"cm, speed {SPEED_RANGE[0]}..{SPEED_RANGE[1]} cm/s)")

    @property
    def step(self) -> IntArray:
        """(3,) the step, cm."""
        return np.array([self.x, self.y, self.z], dtype=np.int64)

    @property
    def command(self) -> str:
        """The SDK command text."""
        return f"go {self.x} {self.y} {self.z} {self.speed}"

    @property
    def duration(self) -> float:
        """Seconds the move takes at its speed (accelerations aside)."""
        return float(np.linalg.norm(self.step)) / self.speed


def go_speed(metres_per_second: float) -> int:
    """A speed in m/s as a ``go`` speed in cm/s, clamped to :data:`SPEED_RANGE`."""
    return int(np.clip(round(100.0 * metres_per_second), *SPEED_RANGE))


def is_long_enough(step: ArrayLike) -> bool:
    """Whether a step (3,) in cm has a component beyond +-:data:`GO_MIN_CM`."""
    return bool(np.max(np.abs(np.asarray(step))) > GO_MIN_CM)


def _pieces(start: IntArray, end: IntArray) -> list[IntArray]:
    """Points after each equal piece of start -> end with at most GO_MAX_CM per axis."""
    count = max(1, -(-int(np.max(np.abs(end - start))) // GO_MAX_CM))
    return [start + np.rint((end - start) * k / count).astype(np.int64)
            for k in range(1, count + 1)]


def _detour(start: IntArray, end: IntArray, allowed: Allowed,
            segments: range) -> list[IntArray] | None:
    """The middle and end points of two allowed moves start -> middle -> end in place of
    ``segments``, or None."""
    for direction in _DETOURS:
        middle = end + DETOUR_CM * direction
        if allowed(start, middle, segments) and allowed(middle, end, segments):
            return [middle, end]
    return None


def go_moves(points: ArrayLike, speed: int, allowed: Allowed,
             rule: Rule = _the_fence) -> list[Move]:
    """Allowed ``go`` moves from ``points[0]`` through the others to ``points[-1]``.

    Args:
        points: (N, 3) takeoff-frame points in whole centimetres; the first is where the
            drone is. Points too close to the previous one are merged away or reached
            by a detour (see the module's description).
        speed: cm/s, within :data:`SPEED_RANGE`.
        allowed: the verdict on a straight move (see :data:`Allowed`).
        rule: names what ``allowed`` keeps a move in, for the messages.

    Raises:
        MoveError: a step that is not allowed, or a short one that can be neither
            merged nor reached by a detour.
    """
    pts = np.asarray(points, dtype=np.int64).reshape(-1, 3)
    here, at = pts[0], 0  # where the drone is, and the waypoint that is
    reached: list[IntArray] = []
    i = 1
    while i < len(pts):
        target = pts[i]
        if np.array_equal(target, here):
            at, i = i, i + 1
            continue
        if not is_long_enough(target - here):
            if i + 1 < len(pts) and allowed(here, pts[i + 1], range(at, i + 1)):
                i += 1  # merged: fly straight on to the next waypoint
                continue
            detour = _detour(here, target, allowed, range(at, i))
            if detour is None:
                raise MoveError(f"no allowed go move from {here.tolist()} to "
                                f"{target.tolist()} cm: the step is within +-{GO_MIN_CM} "
                                "cm and neither merging nor a detour stays in "
                                f"{rule(range(at, i))}")
            steps = detour
        else:
            steps = _pieces(here, target)
        for end in steps:
            if not allowed(here, end, range(at, i)):
                raise MoveError(f"go move from {here.tolist()} to {end.tolist()} cm "
                                f"leaves {rule(range(at, i))}")
            reached.append(end)
            here = end
        at, i = i, i + 1
    return _moves_between([pts[0], *reached], speed)


def _moves_between(points: Sequence[IntArray], speed: int) -> list[Move]:
    """The moves from each point (3,) cm to the next, at ``speed`` cm/s."""
    return [Move(*(int(v) for v in b - a), speed=speed)
            for a, b in pairwise(points)]
