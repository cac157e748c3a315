"""The tables of a mission file (:class:`Section`\\ s of :class:`~.config.MissionConfig`):
unknown keys refused, every value checked (:mod:`.checks`)."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, ConfigDict, ValidationInfo, field_validator

from quadnav.control.registry import DEFAULT_CONTROLLER, controller_class
from quadnav.limits import (
    ACCELERATION,
    FORCE,
    GUSTS,
    MARGIN,
    PLAN_TIME,
    RATE,
    SAMPLES,
    SEED,
    SETTLE,
    SPREAD,
    STALL_FRACTION,
    Speed,
    is_number,
)
from quadnav.mission import DEFAULT_ACCELERATION, DEFAULT_IMPROVE, DEFAULT_SPEED, DEFAULT_TIME_CAP
from quadnav.missionconfig.checks import (
    Point,
    TextOrTable,
    choice,
    fail,
    file,
    flag,
    number,
    text,
    top_speed,
    vector,
)
from quadnav.planning import get_planner
from quadnav.planning.stall import DEFAULT_STALL_FRACTION, DEFAULT_STALL_SAMPLES
from quadnav.sim.settings import SimSettings
from quadnav.sim.wind import wind_maker
from quadnav.trajectory.generate import METHODS, TIMINGS
from quadnav.trajectory.references.builtin import DURATION
from quadnav.trajectory.references.plain import load_trajectory_class

#: The parts of the vehicle a spread scales, in the order its factors are drawn.
SPREAD_PARTS = ("mass", "thrust", "drag")


class Section(BaseModel):
    """A table of a mission file: unknown keys refused, values immutable."""

    model_config = ConfigDict(extra="forbid", frozen=True)


class Query(Section):
    """``[query]``: where the mission flies from and to, and the margin it keeps.

    Attributes:
        start: (x, y, z) m, or None: the start/goal file's, else the map's own.
        goal: likewise.
        start_goal: an RBE595 start/goal file or a course one (``course:NAME``).
        margin: m, or None: the map's own, else 0.2
            (:meth:`~quadnav.world.World.margin_for`).
    """

    start: Point = None
    goal: Point = None
    start_goal: Annotated[str | None, text(optional=True), BeforeValidator(file)] = None
    margin: Annotated[float | None, number(MARGIN, optional=True)] = None


class Planner(Section):
    """``[planner]``: the path search and its budget (the seed is the mission's).

    Attributes:
        name: a planner's name (``rrtstar``, ``ompl:NAME``) or a plug-in spec.
        time: wall-time cap of the search, s.
        iterations: samples in all (0: no cap).
        improve: samples of improvement after the first path, at most.
        stall: stop once the best length has shortened by at most ``stall_fraction`` over
            this many samples (:mod:`~quadnav.planning.stall`); 0: no such rule, a fixed
            budget.
        stall_fraction: that fraction of the best length.
        refine: shortcut and smooth the path.
    """

    name: Annotated[str, text(get_planner), BeforeValidator(file)] = "rrtstar"
    time: Annotated[float, number(PLAN_TIME)] = DEFAULT_TIME_CAP
    iterations: Annotated[int, number(SAMPLES)] = 0
    improve: Annotated[int, number(SAMPLES)] = DEFAULT_IMPROVE
    stall: Annotated[int, number(SAMPLES)] = DEFAULT_STALL_SAMPLES
    stall_fraction: Annotated[float, number(STALL_FRACTION)] = DEFAULT_STALL_FRACTION
    refine: Annotated[bool, BeforeValidator(flag)] = True


def _reference_class(text: str) -> None:
    """The check of a reference: a trajectory class, loaded, to be built from a path."""
    load_trajectory_class(text, with_points=True)


class Trajectory(Section):
    """``[trajectory]``: the trajectory stage.

    Attributes:
        method: a trajectory method (:data:`~quadnav.trajectory.generate.METHODS`).
        timing: how its segments are timed (:data:`~quadnav.trajectory.generate.TIMINGS`).
        speed: top speed, m/s, or ``"max"``: as fast as the vehicle can follow.
        accel: largest acceleration, m/s^2 (ignored with ``"max"``).
        reference: a trajectory class of your own (a plug-in spec,
            :mod:`quadnav.trajectory.references.plain`) flown instead of the trajectory made through
            the path; None: that trajectory.
        duration: how long ``reference`` is flown, s; None: as long as it says it lasts.
    """

    method: Annotated[str, text(choice(METHODS.names))] = "minsnap"
    timing: Annotated[str, text(choice(lambda: TIMINGS))] = "fastest"
    speed: Annotated[Speed, BeforeValidator(top_speed)] = DEFAULT_SPEED
    accel: Annotated[float, number(ACCELERATION)] = DEFAULT_ACCELERATION
    reference: Annotated[str | None, text(_reference_class, optional=True),
                         BeforeValidator(file)] = None
    duration: Annotated[float | None, number(DURATION, optional=True)] = None

    @field_validator("duration")
    @classmethod
    def _with_reference(cls, duration: float | None, info: ValidationInfo) -> float | None:
        if duration is not None and info.data.get("reference") is None:
            raise fail("applies only to a trajectory class of your own (--reference, a mission "
                       "file's trajectory.reference)")
        return duration


class Controller(Section):
    """``[controller]``: what flies the vehicle.

    Attributes:
        name: a controller's name (``cascade``, ``se3``) or a plug-in spec.
        gains: its gains over those tuned for the vehicle: a gains TOML file, a course gain
            table's name, or a table of keys; None: the vehicle's own.
    """

    name: Annotated[str, text(controller_class), BeforeValidator(file)] = DEFAULT_CONTROLLER
    gains: TextOrTable = None


class Simulation(Section):
    """``[simulation]``: rates, the settling time and the flight's own seed.

    Attributes:
        physics_rate: RK4 steps per second, Hz.
        control_rate: controller updates per second, Hz.
        settle: time flown after the reference ends, s.
        seed: the seed of the gusts and the vehicle spread alone; None: the mission's
            (which seeds the planner too). A batch with separate planner and simulation
            seeds sets it.
    """

    physics_rate: Annotated[float, number(RATE)] = SimSettings.physics_rate
    control_rate: Annotated[float, number(RATE)] = SimSettings.control_rate
    settle: Annotated[float, number(SETTLE)] = SimSettings.settle_time
    seed: Annotated[int | None, number(SEED, optional=True)] = None


class Spread(Section):
    """How far the flown vehicle may differ from the nominal one: its mass, thrust
    coefficient and drag are each scaled by a factor drawn uniformly in [1 - f, 1 + f]
    from the mission's seed (:func:`spread_factors`); ``spread = 0.1`` sets all three."""

    mass: Annotated[float, number(SPREAD)] = 0.0
    thrust: Annotated[float, number(SPREAD)] = 0.0
    drag: Annotated[float, number(SPREAD)] = 0.0

    @property
    def label(self) -> str:
        """``0.1`` when the three fractions agree, else ``mass=0.1,thrust=0.05,drag=0.2``."""
        if self.mass == self.thrust == self.drag:
            return f"{self.mass:g}"
        return ",".join(f"{part}={getattr(self, part):g}" for part in SPREAD_PARTS)


def spread_table(value: Any) -> Any:
    """A spread as its table: one fraction for all three parts, or a table of them."""
    if isinstance(value, dict | Spread):
        return value
    if not is_number(value):
        raise fail(f"expected a fraction {SPREAD.describe()} or a table of "
                   f"{', '.join(SPREAD_PARTS)}, got {value!r}")
    return dict.fromkeys(SPREAD_PARTS, value)


class Disturbances(Section):
    """``[disturbances]``: what pushes the vehicle off its reference.

    Attributes:
        wind: (3,) steady force, N, world frame.
        wind_model: a plain-Python wind (a plug-in spec) beside that force; None: none.
        gusts: random force's standard deviation per axis, N, redrawn from the seed.
        spread: the vehicle spread.
    """

    wind: Annotated[tuple[float, float, float], vector(FORCE, "fx, fy, fz")] = (0.0, 0.0, 0.0)
    wind_model: Annotated[str | None, text(wind_maker, optional=True),
                          BeforeValidator(file)] = None
    gusts: Annotated[float, number(GUSTS)] = 0.0
    spread: Annotated[Spread, BeforeValidator(spread_table)] = Spread()


