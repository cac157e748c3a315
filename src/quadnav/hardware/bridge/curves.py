"""A trajectory as the Tello SDK's ``curve`` and ``go`` commands (``--mode curves``).

:func:`fit_commands` follows a trajectory, sampled in whole centimetres of the takeoff
frame, greedily: from where the drone is, the longest stretch that one command flies
within :data:`TOLERANCE_CM` of every sample of the stretch — a ``curve`` through the
stretch's middle sample to its last (its radius within the SDK's 0.5 to 10 m), else a
straight ``go`` — and that the caller's ``allowed`` accepts (the plan checks every
centimetre of the arc, or the straight move, against the geofence). A curved trajectory
is so flown with far fewer commands than ``rc`` sticks need (20 a second) and much closer
to it than ``go`` moves through the route's corners.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from quadnav.hardware.arc import Arc
from quadnav.hardware.bridge.frames import IntArray
from quadnav.hardware.bridge.moves import Move, MoveError
from quadnav.hardware.sdk import SdkError, parse_command
from quadnav.planning.result import nearest_on_polyline

#: Farthest a command's path may come from the trajectory's samples it stands for, cm.
TOLERANCE_CM = 5.0
#: Slowest and fastest ``curve`` speed, cm/s.
CURVE_SPEED = (10, 60)
#: Samples skipped between the stretch ends tried, longest first.
STRIDE = 4

#: ``arc_allowed(start, via, end)``: whether the arc through three takeoff-frame points in
#: whole centimetres may be flown; ``line_allowed(start, end)`` likewise for a straight move.
ArcAllowed = Callable[[IntArray, IntArray, IntArray], bool]
LineAllowed = Callable[[IntArray, IntArray], bool]


@dataclass(frozen=True)
class Curve:
    """One ``curve x1 y1 z1 x2 y2 z2 speed`` command: an arc through ``via`` to ``end``
    (takeoff-frame steps from where it starts, cm) at ``speed`` cm/s."""

    via: tuple[int, int, int]
    end: tuple[int, int, int]
    speed: int

    @property
    def step(self) -> IntArray:
        """(3,) from its start to its end, cm."""
        return np.array(self.end, dtype=np.int64)

    @property
    def command(self) -> str:
        """The SDK command text."""
        return "curve " + " ".join(map(str, (*self.via, *self.end, self.speed)))

    @property
    def duration(self) -> float:
        """Seconds the arc takes at its speed (accelerations aside)."""
        return Arc(np.zeros(3), self.via, self.end).length / self.speed


def _sdk_flies(command: str) -> bool:
    """Whether the Tello SDK takes ``command`` (a ``curve``: its ranges, its shortest step
    and its radii), as :func:`~quadnav.hardware.sdk.parse_command` reads it."""
    try:
        parse_command(command)
    except SdkError:
        return False
    return True


def _off_line(points: np.ndarray, start: IntArray, end: IntArray) -> float:
    """Largest distance, cm, of ``points`` (K, 3) from the segment start -> end."""
    foot = nearest_on_polyline(points, np.stack([start, end]))
    return float(np.linalg.norm(points - foot, axis=1).max())


def fit_commands(samples: np.ndarray, go_speed: int, curve_speed: int,
                 arc_allowed: ArcAllowed, line_allowed: LineAllowed) -> list[Move | Curve]:
    """``go`` and ``curve`` commands from ``samples[0]`` to ``samples[-1]`` following the
    samples (N >= 2, 3) of a trajectory, takeoff frame, cm (the ends whole centimetres).

    Raises:
        MoveError: a stretch that no allowed command follows within the tolerance.
    """
    samples = np.asarray(samples, dtype=np.float64)
    here, i, last = np.rint(samples[0]).astype(np.int64), 0, len(samples) - 1
    commands: list[Move | Curve] = []
    while i < last:
        found = None
        for j in range(last, i, -STRIDE) if last - i > STRIDE else range(last, i, -1):
            found = _command(samples, here, i, j, go_speed, curve_speed, arc_allowed,
                             line_allowed)
            if found is not None:
                break
        if found is None:
            raise MoveError(f"curves: no allowed go or curve follows the trajectory within "
                            f"{TOLERANCE_CM:g} cm from {here.tolist()} cm (takeoff frame)")
        command, here, i = found
        commands.append(command)
    return commands


def _command(samples: np.ndarray, here: IntArray, i: int, j: int, go_speed: int,
             curve_speed: int, arc_allowed: ArcAllowed, line_allowed: LineAllowed
             ) -> tuple[Move | Curve, IntArray, int] | None:
    """The command from ``here`` (cm) standing for samples ``i..j``, the point it ends at
    and ``j``; None when neither a curve nor a go does."""
    end = np.rint(samples[j]).astype(np.int64)
    stretch = samples[i:j + 1]
    via = np.rint(samples[(i + j) // 2]).astype(np.int64)
    curve = Curve(tuple(map(int, via - here)), tuple(map(int, end - here)), curve_speed)
    if _sdk_flies(curve.command):
        arc = Arc(here, via, end)
        if arc.distances(stretch).max() <= TOLERANCE_CM and arc_allowed(here, via, end):
            return curve, end, j
    try:
        move = Move(*map(int, end - here), go_speed)  # refused as the SDK refuses it
    except MoveError:
        return None
    if _off_line(stretch, here, end) <= TOLERANCE_CM and line_allowed(here, end):
        return move, end, j
    return None
