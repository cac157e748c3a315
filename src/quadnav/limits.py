"""The stated range of every number quadnav accepts, in one place.

Each range is wide enough for any map, vehicle or run a course or a lab would use, and
narrow enough that nothing a user asks for can overflow or allocate more than a few
hundred megabytes. Things that grow with a product of settings have a bound of their
own: samples (duration / interval), simulation steps (duration x rate), tree vertices.

The library checks these in the settings' and :class:`~quadnav.world.World`'s
constructors (raising :class:`~quadnav.errors.QuadnavError`); the command line checks
each flag as it is parsed, so the message names the flag.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from quadnav.errors import QuadnavError


def is_number(value: object, finite: bool = False) -> bool:
    """Whether ``value`` is a number as JSON and TOML read one (an int or a float, never a
    bool); with ``finite``, also neither infinite nor NaN."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return False
    return not finite or math.isfinite(value)


def format_number(value: float, grouped: bool = True) -> str:
    """The shortest text that reads back as exactly ``value`` (``3`` rather than ``3.0``;
    ``10000.001``, never a rounded ``10000`` that would contradict the range it is refused
    by); whole numbers with thousands separators when ``grouped`` (for messages; a map
    file writes them plain)."""
    if isinstance(value, int) or (math.isfinite(value) and float(value).is_integer()
                                  and abs(value) < 1e15):
        return f"{int(value):,}" if grouped else str(int(value))
    return repr(float(value))


@dataclass(frozen=True)
class Range:
    """The accepted values of one setting: ``low`` (or above it) to ``high``, inclusive.

    Attributes:
        low: least value (excluded when ``above_low``).
        high: greatest value.
        unit: unit shown after the numbers, e.g. ``m/s``.
        above_low: values must be greater than ``low``.
        whole: values must be whole numbers.
    """

    low: float
    high: float
    unit: str = ""
    above_low: bool = False
    whole: bool = False

    def __contains__(self, value: object) -> bool:
        if not is_number(value):
            return False
        if self.whole and not (isinstance(value, int) or float(value).is_integer()):
            return False
        if not math.isfinite(value):
            return False
        return (value > self.low if self.above_low else value >= self.low) and value <= self.high

    def describe(self) -> str:
        """The range in words, e.g. ``0.01 to 100 m/s`` or ``above 0, at most 3,600 s``."""
        unit = f" {self.unit}" if self.unit else ""
        kind = "a whole number " if self.whole else ""
        low, high = format_number(self.low), format_number(self.high)
        if self.above_low:
            return f"{kind}above {low}, at most {high}{unit}"
        return f"{kind}from {low} to {high}{unit}"

    def check(self, value: float, what: str) -> float:
        """``value`` if it is in range; otherwise QuadnavError naming ``what``."""
        if value not in self:
            shown = format_number(value) if isinstance(value, int | float) else repr(value)
            raise QuadnavError(f"{what}: expected {self.describe()}, got {shown}")
        return value


# ------------------------------------------------------------------------- maps
#: Every coordinate of a boundary, start or goal, metres (10 km each way).
COORDINATE = Range(-1e4, 1e4, "m")
#: Every coordinate of a :class:`~quadnav.world.World` made in Python, metres: the working
#: range of the geometry, wider than :data:`COORDINATE` so that helper worlds may widen a
#: map's boundary.
WORLD_COORDINATE = Range(-1e7, 1e7, "m")
#: Each side of a map's boundary box, metres.
BOUNDARY_SIDE = Range(1e-3, 2e4, "m")
#: A safety margin, metres.
MARGIN = Range(0.0, 100.0, "m")
#: Blocks in one map.
MAX_BLOCKS = 1_000_000
#: Size of a map, start/goal or path file, bytes.
MAX_FILE_BYTES = 128 * 1024 * 1024
#: Characters on one line of a text map or path file.
MAX_LINE = 10_000
#: Waypoints in a path file.
MAX_WAYPOINTS = 100_000

# --------------------------------------------------------------------- planning
#: A search's time budget, s.
PLAN_TIME = Range(0.0, 3600.0, "s", above_low=True)
#: Samples of a path search (RRT*'s tree never holds more vertices than this).
PLAN_ITERATIONS = Range(1, 5_000_000, whole=True)
#: Samples of a search's budget (--iterations, --improve): 0 (for --iterations: no cap
#: of its own) or a number.
SAMPLES = Range(0, PLAN_ITERATIONS.high, whole=True)
#: The stretch of a search's stall rule, samples (quadnav.planning.stall).
STALL_SAMPLES = Range(1, PLAN_ITERATIONS.high, whole=True)
#: The fraction of its best length by which a search must shorten over that stretch.
STALL_FRACTION = Range(0.0, 0.5)
#: Extensions of a kinodynamic search.
KINO_ITERATIONS = Range(1, 1_000_000, whole=True)
#: Random seeds.
SEED = Range(0, 2**63 - 1, whole=True)
#: A step, a goal tolerance or a goal region's radius, metres.
LENGTH = Range(1e-3, 1e4, "m")

# ------------------------------------------------------------------ trajectories
#: A trajectory's top speed, m/s.
SPEED = Range(0.01, 100.0, "m/s")
#: The top speed ``max``: as fast as the vehicle can follow on the path.
MAX_SPEED = "max"
#: A mission's top speed: m/s in :data:`SPEED`, or :data:`MAX_SPEED`.
Speed = float | Literal["max"]
#: A vehicle spread: the largest fraction by which mass, thrust or drag may differ.
SPREAD = Range(0.0, 0.9)
#: A trajectory's largest acceleration, m/s^2.
ACCELERATION = Range(0.01, 1000.0, "m/s^2")
#: Sample interval of written trajectories, s.
SAMPLE_INTERVAL = Range(1e-4, 1.0, "s")
#: Samples of one trajectory (its duration / the interval, + 1).
MAX_SAMPLES = 1_000_000
#: Longest trajectory flown, s (longer than any quadrotor's battery lasts).
MAX_DURATION = 3600.0

# ------------------------------------------------------------------- simulation
#: Each gain of a controller's table, per axis, and each integral bound, in its loop's units:
#: far above any gain that flies, low enough that no step's arithmetic overflows.
GAIN = Range(0.0, 10_000.0)
#: Physics and control rates, Hz.
RATE = Range(10.0, 100_000.0, "Hz")
#: Time flown after the trajectory ends, s.
SETTLE = Range(0.0, 60.0, "s")
#: A steady wind force per axis, N.
FORCE = Range(-100.0, 100.0, "N")
#: Standard deviation of the gusts per axis, N.
GUSTS = Range(0.0, 100.0, "N")
#: Controller steps of one simulated flight (each keeps about 200 bytes of reference,
#: disturbance and noise): (trajectory + settling) x control rate.
MAX_CONTROL_STEPS = 2_000_000
#: Physics steps of one simulated flight: (trajectory + settling) x physics rate.
MAX_PHYSICS_STEPS = 20_000_000

# --------------------------------------------------------------------- headings
#: A heading in degrees.
HEADING_DEGREES = Range(-360.0, 360.0, "degrees")
#: A heading in radians.
HEADING_RADIANS = Range(-2 * math.pi, 2 * math.pi, "rad")

# ------------------------------------------------------------------------ other
#: Probabilities and other fractions.
UNIT_INTERVAL = Range(0.0, 1.0)
#: Emulated (or drone) seconds per wall-clock second of a Tello flight.
TIME_SCALE = Range(0.01, 100.0)


def speed_value(value: object) -> Speed | None:
    """``value`` as a mission's top speed (:data:`Speed`): a number in :data:`SPEED`, or
    ``max`` in any case; None when it is neither (the one rule of every command, mission
    file and batch spec)."""
    if isinstance(value, str):
        return MAX_SPEED if value.strip().lower() == MAX_SPEED else None
    return float(value) if value in SPEED else None


def speed_text(speed: Speed) -> str:
    """``speed`` as a flag gives it: ``2``, ``0.5`` or ``max``."""
    return speed if speed == MAX_SPEED else f"{speed:g}"


def check_duration(duration: float, advice: str, at_least: bool = False) -> None:
    """QuadnavError if a trajectory of ``duration`` s is longer than :data:`MAX_DURATION`.

    ``at_least``: ``duration`` is a lower bound (e.g. path length / top speed).
    ``advice`` says which setting shortens it.
    """
    if not duration <= MAX_DURATION:
        lasts = "would last at least" if at_least else "lasts"
        raise QuadnavError(f"the trajectory {lasts} {duration:.6g} s, longer than the "
                           f"{MAX_DURATION:g} s a trajectory may last: {advice}")


def check_count(count: float, limit: int, what: str, advice: str) -> None:
    """QuadnavError if ``count`` (of samples, steps, ...) exceeds ``limit``.

    The message says what gives the count, e.g. ``"a 120 s trajectory sampled every
    0.0001 s gives samples"``, and ``advice``: which settings lower it.
    """
    if not count <= limit:
        shown = format_number(math.ceil(count)) if math.isfinite(count) else "too many"
        raise QuadnavError(f"{what}: {shown}, at most {format_number(limit)}; {advice}")
