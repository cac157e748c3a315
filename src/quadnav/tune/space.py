"""What ``quadnav tune`` searches over: :class:`Knob`, the search spaces, and gains from a
point of the space.

A knob sets one gain (or limit) of :class:`~quadnav.control.gains.Gains` on some axes at
once: ``velocity.kp.xy`` sets the velocity loop's proportional gain on x and y together
(the vehicle is symmetric, so the two horizontal axes share their gains, which halves
the space), ``velocity.kp.z`` the vertical one. Proportional gains are searched on a log
scale (they span decades); integral and derivative gains on a linear one from 0, so
"none" is a value the search can reach.

Spaces (:data:`SPACES`):

* ``outer`` — the 18 position and velocity gains the course tunes by hand, as 12 knobs
  (kp, ki, kd of each loop, horizontal and vertical);
* ``cascade`` (default) — those, the attitude gains, the roll/pitch rate PID and the
  tilt limit: 18 knobs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from quadnav.config import as_plain, from_table
from quadnav.control.gains import Gains
from quadnav.errors import QuadnavError

#: Axis groups a knob can set, by the suffix of its name.
AXES = {"xy": (0, 1), "z": (2,), "rp": (0, 1), "yaw": (2,)}


@dataclass(frozen=True)
class Knob:
    """One searched value.

    Attributes:
        name: ``loop.gain.axes`` (``velocity.kp.xy``), ``vector.axes``
            (``attitude_kp.rp``) or ``limits.field`` (``limits.tilt_max_deg``).
        low: least value (in the gain's unit).
        high: greatest value.
        log: searched on a log scale (``low`` > 0).
    """

    name: str
    low: float
    high: float
    log: bool = False

    def __post_init__(self) -> None:
        if not (0 <= self.low < self.high and (self.low > 0 or not self.log)):
            raise ValueError(f"knob {self.name}: bad range {self.low} to {self.high}")

    @property
    def keys(self) -> tuple[list[str], tuple[int, ...] | None]:
        """The TOML key path of the value set and the axes set (None: a scalar)."""
        *path, last = self.name.split(".")
        if last in AXES:
            return path, AXES[last]
        return [*path, last], None

    def read(self, gains: Gains) -> float:
        """The value this knob has in ``gains`` (the first of its axes), clipped into
        its range."""
        path, axes = self.keys
        value: Any = as_plain(gains)
        for key in path:
            value = value[key]
        value = float(value if axes is None else value[axes[0]])
        return min(max(value, self.low), self.high)


def _pid_knobs(loop: str, kp: tuple[float, float], ki: float, kd: float,
               axes: tuple[str, ...]) -> list[Knob]:
    """kp (log, from ``kp``'s range), ki in [0, ki], kd in [0, kd] per axis group."""
    return [knob for axis in axes for knob in (
        Knob(f"{loop}.kp.{axis}", *kp, log=True), Knob(f"{loop}.ki.{axis}", 0.0, ki),
        Knob(f"{loop}.kd.{axis}", 0.0, kd))]


#: The course's 18 hand-tuned gains, x and y shared (12 knobs).
OUTER = (*_pid_knobs("position", (0.1, 20.0), 3.0, 1.0, ("xy", "z")),
         *_pid_knobs("velocity", (0.3, 30.0), 10.0, 1.0, ("xy", "z")))
#: The whole cascade: the outer loops, attitude, the roll/pitch rate PID, the tilt limit.
CASCADE = (*OUTER, Knob("attitude_kp.rp", 1.0, 40.0, log=True),
           Knob("attitude_kp.yaw", 1.0, 20.0, log=True),
           *_pid_knobs("rate", (3.0, 150.0), 40.0, 1.0, ("rp",)),
           Knob("limits.tilt_max_deg", 15.0, 60.0))
SPACES: dict[str, tuple[Knob, ...]] = {"cascade": CASCADE, "outer": OUTER}


def space_knobs(name: str) -> tuple[Knob, ...]:
    """The knobs of the space ``name``; QuadnavError naming the known ones."""
    if name not in SPACES:
        raise QuadnavError(f"unknown search space {name!r}; expected one of "
                           f"{', '.join(SPACES)}")
    return SPACES[name]


def with_values(gains: Gains, values: dict[str, float]) -> Gains:
    """``gains`` with each knob named in ``values`` set (on all of its axes)."""
    table: dict[str, Any] = {}
    plain = as_plain(gains)
    for name, value in values.items():
        path, axes = Knob(name, 0.0, 1.0).keys
        node, current = table, plain
        for key in path[:-1]:
            node, current = node.setdefault(key, {}), current[key]
        last = path[-1]
        if axes is None:
            node[last] = float(value)
            continue
        vector = list(node.get(last, current[last]))
        for axis in axes:
            vector[axis] = float(value)
        node[last] = vector
    return from_table(gains, table, "tuned gains")


def starting_point(gains: Gains, knobs: tuple[Knob, ...]) -> dict[str, float]:
    """The point of the space closest to ``gains`` (each knob's value, clipped into its
    range): the first trial of a study, so the search never ends worse than it began."""
    return {knob.name: knob.read(gains) for knob in knobs}


def describe(knob: Knob) -> str:
    """``velocity.kp.xy in 0.3 to 30 (log)`` for help texts and reports."""
    scale = " (log)" if knob.log else ""
    return f"{knob.name} in {knob.low:g} to {knob.high:g}{scale}"

