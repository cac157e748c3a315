"""One mission, described once: :class:`MissionConfig`, what ``fly``, ``batch`` (each of its
missions), ``tune``, ``tello fly``, ``refly`` and the library build a mission from, and what a
run folder keeps as ``mission.toml`` so that it flies again exactly.

A mission file is TOML; every key is optional, and those left out are ``quadnav fly``'s
defaults::

    map = "course:rbe595/map1"    # a map file, a built-in world spec or a course map
    seed = 0                      # the planner's, the gusts', the vehicle spread's
    vehicle = "tello"             # a preset or a vehicle TOML file, or a [vehicle] table

    [query]
    start = [0.1, -4.9, 0.2]      # m; default: the start/goal file's, else the map's own
    goal = [8.0, 18.0, 3.0]
    start_goal = "start_goal.txt" # an RBE595 start/goal file or a course one
    margin = 0.2                  # m; default: the map's own, else 0.2

    [planner]
    name = "rrtstar"              # a planner's name (ompl:NAME) or a plug-in spec
    time = 10.0                   # s, the search's wall-time cap
    iterations = 0                # samples in all, 0: no cap
    improve = 50000               # samples after the first path
    refine = true                 # shortcut and smooth the path

    [trajectory]
    method = "minsnap"
    timing = "fastest"
    speed = 2.0                   # m/s, or "max"
    accel = 3.0                   # m/s^2
    reference = "my_ref.py:Circle(radius=2)"   # a plain-Python reference flown instead

    [controller]
    name = "cascade"              # or "se3", or a plug-in spec
    gains = "my_gains.toml"       # a gains file, a course gain table, or a [controller.gains] table

    [simulation]
    physics_rate = 1000.0         # Hz
    control_rate = 1000.0         # Hz
    settle = 2.0                  # s flown after the reference ends

    [disturbances]
    wind = [0.0, 0.0, 0.0]        # N, world frame
    wind_model = "my_wind.py:Gusty(speed=3)"   # a plain-Python wind, beside the force
    gusts = 0.0                   # N, standard deviation per axis
    spread = 0.0                  # or {mass = 0.1, thrust = 0.05, drag = 0.2}

Every key is checked by a pydantic schema against the ranges the flags have
(:mod:`quadnav.limits`); a mistake in a file is one :class:`~quadnav.errors.QuadnavError`
naming the file, the line and the key (:func:`read_mission`). Plug-ins (the planner, the
controller, the reference, the wind model, a vehicle named by a spec) travel as their text
and are loaded where they are used. Relative paths are resolved against the file's folder.

:meth:`MissionConfig.settings` is the one builder of
:class:`~quadnav.mission.MissionSettings` and :meth:`MissionConfig.problem` of the checked
query; :meth:`MissionConfig.flown` is what a run folder keeps (:meth:`MissionConfig.toml`).
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    PrivateAttr,
    ValidationError,
    ValidationInfo,
)
from pydantic_core import PydanticCustomError

from quadnav.config import as_plain, read_toml
from quadnav.control.registry import DEFAULT_CONTROLLER, controller_factory, controller_gains
from quadnav.errors import QuadnavError
from quadnav.limits import (
    ACCELERATION,
    COORDINATE,
    FORCE,
    GUSTS,
    MARGIN,
    MAX_SPEED,
    PLAN_TIME,
    RATE,
    SAMPLES,
    SEED,
    SETTLE,
    SPEED,
    SPREAD,
    Range,
    Speed,
    speed_value,
)
from quadnav.mission import (
    DEFAULT_ACCELERATION,
    DEFAULT_IMPROVE,
    DEFAULT_SPEED,
    DEFAULT_TIME_CAP,
    Mission,
    MissionSettings,
    fly_problem,
)
from quadnav.planning import PlannerSettings, PlanningProblem, get_planner, make_problem
from quadnav.plugins import parse_spec
from quadnav.sim.settings import SimSettings, default_record_rate
from quadnav.trajectory.generate import METHODS, TIMINGS, TrajectorySettings
from quadnav.vehicle.params import (
    DEFAULT_PRESET,
    VehicleParams,
    load_params,
    params_from_table,
    preset_names,
)
from quadnav.world import World, load_world
from quadnav.world.builtin import DEFAULT_WORLD_SPEC
from quadnav.world.startgoal import query_ends

#: The file a run folder keeps its mission in.
MISSION_FILE = "mission.toml"
#: The seed's stream of the vehicle spread's factors (a batch's query draws use another).
SPREAD_STREAM = 1
#: The parts of the vehicle a spread scales, in the order its factors are drawn.
SPREAD_PARTS = ("mass", "thrust", "drag")


# ------------------------------------------------------------------------ checked values
def _fail(message: str) -> PydanticCustomError:
    return PydanticCustomError("quadnav", message)


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _number(allowed: Range, optional: bool = False) -> BeforeValidator:
    """A number in ``allowed`` (a whole one if it says so), or None if ``optional``."""
    def check(value: Any) -> float | None:
        if value is None and optional:
            return None
        if not _is_number(value) or value not in allowed:
            raise _fail(f"expected {allowed.describe()}, got {value!r}")
        return int(value) if allowed.whole else float(value)
    return BeforeValidator(check)


def _vector(allowed: Range, names: str, optional: bool = False) -> BeforeValidator:
    """Three numbers, each in ``allowed``, written ``[names]``, or None if ``optional``."""
    def check(value: Any) -> tuple[float, float, float] | None:
        if value is None and optional:
            return None
        if not (isinstance(value, list | tuple) and len(value) == 3
                and all(_is_number(v) and v in allowed for v in value)):
            raise _fail(f"expected [{names}], each {allowed.describe()}, got {value!r}")
        x, y, z = (float(v) for v in value)
        return x, y, z
    return BeforeValidator(check)


def _text(check_name: Callable[[str], object] | None = None,
          optional: bool = False) -> BeforeValidator:
    """A string, checked by ``check_name`` (QuadnavError for a bad one) if given, or None
    if ``optional``."""
    def check(value: Any) -> str | None:
        if value is None and optional:
            return None
        if not isinstance(value, str) or not value.strip():
            raise _fail(f"expected a string, got {value!r}")
        if check_name is not None:
            try:
                check_name(value)
            except QuadnavError as error:
                if getattr(error, "details", None):
                    raise  # a plug-in's own traceback: shown as it is
                raise _fail(str(error)) from None
        return value
    return BeforeValidator(check)


def _choice(names: Callable[[], list[str] | tuple[str, ...]]) -> Callable[[str], None]:
    def check(value: str) -> None:
        if value not in names():
            raise QuadnavError(f"expected one of {', '.join(names())}, got {value!r}")
    return check


def _flag(value: Any) -> bool:
    if not isinstance(value, bool):
        raise _fail(f"expected true or false, got {value!r}")
    return value


def _speed(value: Any) -> Speed:
    speed = speed_value(value) if _is_number(value) or isinstance(value, str) else None
    if speed is None:
        raise _fail(f"expected {SPEED.describe()} or \"max\", got {value!r}")
    return speed


def _plugin_text(kind: str) -> Callable[[str], None]:
    """A plug-in named by its text (checked for form here, loaded where it is used)."""
    return lambda value: parse_spec(value, kind)


def _file(value: Any, info: ValidationInfo) -> Any:
    """A string naming an existing file relative to the mission file's folder: that file's
    absolute path; any other value as it is (a preset, a built-in world, a course name)."""
    folder = (info.context or {}).get("folder")
    if isinstance(value, str) and folder is not None and not Path(value).is_absolute():
        path = Path(folder) / value
        if path.is_file():
            return os.path.abspath(path)
    return value


def _table_or_text(value: Any) -> str | dict | None:
    if value is None or isinstance(value, dict):
        return value
    if isinstance(value, str) and value.strip():
        return value
    raise _fail(f"expected a name, a file or a table, got {value!r}")


#: A point, m, or None: the mission's default for it.
Point = Annotated[tuple[float, float, float] | None,
                  _vector(COORDINATE, "x, y, z", optional=True)]
#: A file (resolved against the mission file's folder) or a name.
FileOrName = Annotated[str, _text(), BeforeValidator(_file)]
#: A file (likewise), a name or a table of keys, or None: the mission's default.
TextOrTable = Annotated[str | dict | None, BeforeValidator(_table_or_text),
                        BeforeValidator(_file)]


class _Source:
    """Where a mission comes from, for messages: its name and, for a file, its text."""

    def __init__(self, name: str, text: str | None = None,
                 given: Mapping[str, str] | None = None) -> None:
        self.name = name
        self.text = text
        self.given = dict(given or {})

    def where(self, path: list[str]) -> str:
        """``FILE:LINE: dotted.key``, the line where the key ``path`` (or the nearest
        table that holds it) is set (without a line when none is found); for a key set
        on top of the file (:meth:`MissionConfig.with_changes`), the name it was given."""
        dotted = ".".join(path)
        if dotted in self.given:
            return self.given[dotted]
        line = _key_line(self.text or "", path)
        place = self.name if line is None else f"{self.name}:{line}"
        return f"{place}: {'.'.join(path)}"

    def refusal(self, error: Mapping[str, Any]) -> QuadnavError:
        """The first error of a validation as one line."""
        path = [str(part) for part in error["loc"] if not isinstance(part, int)]
        kind = error["type"]
        if kind == "extra_forbidden":
            known = _section(path[:-1]).model_fields
            message = f"unknown key; expected one of {', '.join(known)}"
        elif kind in ("model_type", "model_attributes_type", "dict_type"):
            message = f"expected a table [{'.'.join(path)}], got {error['input']!r}"
        else:
            message = error["msg"]
        return QuadnavError(f"{self.where(path)}: {message}")


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
    start_goal: Annotated[str | None, _text(optional=True), BeforeValidator(_file)] = None
    margin: Annotated[float | None, _number(MARGIN, optional=True)] = None


class Planner(Section):
    """``[planner]``: the path search and its budget (the seed is the mission's).

    Attributes:
        name: a planner's name (``rrtstar``, ``ompl:NAME``) or a plug-in spec.
        time: wall-time cap of the search, s.
        iterations: samples in all (0: no cap).
        improve: samples of improvement after the first path.
        refine: shortcut and smooth the path.
    """

    name: Annotated[str, _text(get_planner)] = "rrtstar"
    time: Annotated[float, _number(PLAN_TIME)] = DEFAULT_TIME_CAP
    iterations: Annotated[int, _number(SAMPLES)] = 0
    improve: Annotated[int, _number(SAMPLES)] = DEFAULT_IMPROVE
    refine: Annotated[bool, BeforeValidator(_flag)] = True


class Trajectory(Section):
    """``[trajectory]``: the trajectory stage.

    Attributes:
        method: a trajectory method (:data:`~quadnav.trajectory.generate.METHODS`).
        timing: how its segments are timed (:data:`~quadnav.trajectory.generate.TIMINGS`).
        speed: top speed, m/s, or ``"max"``: as fast as the vehicle can follow.
        accel: largest acceleration, m/s^2 (ignored with ``"max"``).
        reference: a plain-Python reference (a plug-in spec) flown instead of the
            trajectory made through the path; None: that trajectory.
    """

    method: Annotated[str, _text(_choice(METHODS.names))] = "minsnap"
    timing: Annotated[str, _text(_choice(lambda: TIMINGS))] = "fastest"
    speed: Annotated[Speed, BeforeValidator(_speed)] = DEFAULT_SPEED
    accel: Annotated[float, _number(ACCELERATION)] = DEFAULT_ACCELERATION
    reference: Annotated[str | None, _text(_plugin_text("reference"), optional=True)] = None


class Controller(Section):
    """``[controller]``: what flies the vehicle.

    Attributes:
        name: a controller's name (``cascade``, ``se3``) or a plug-in spec.
        gains: its gains over those tuned for the vehicle: a gains TOML file, a course gain
            table's name, or a table of keys; None: the vehicle's own.
    """

    name: Annotated[str, _text(controller_factory)] = DEFAULT_CONTROLLER
    gains: TextOrTable = None


class Simulation(Section):
    """``[simulation]``: rates and the settling time.

    Attributes:
        physics_rate: RK4 steps per second, Hz.
        control_rate: controller updates per second, Hz.
        settle: time flown after the reference ends, s.
    """

    physics_rate: Annotated[float, _number(RATE)] = SimSettings.physics_rate
    control_rate: Annotated[float, _number(RATE)] = SimSettings.control_rate
    settle: Annotated[float, _number(SETTLE)] = SimSettings.settle_time


class Spread(Section):
    """How far the flown vehicle may differ from the nominal one: its mass, thrust
    coefficient and drag are each scaled by a factor drawn uniformly in [1 - f, 1 + f]
    from the mission's seed (:func:`spread_factors`); ``spread = 0.1`` sets all three."""

    mass: Annotated[float, _number(SPREAD)] = 0.0
    thrust: Annotated[float, _number(SPREAD)] = 0.0
    drag: Annotated[float, _number(SPREAD)] = 0.0

    @property
    def label(self) -> str:
        """``0.1`` when the three fractions agree, else ``mass=0.1,thrust=0.05,drag=0.2``."""
        if self.mass == self.thrust == self.drag:
            return f"{self.mass:g}"
        return ",".join(f"{part}={getattr(self, part):g}" for part in SPREAD_PARTS)


def _spread(value: Any) -> Any:
    if isinstance(value, dict | Spread):
        return value
    if not _is_number(value):
        raise _fail(f"expected a fraction {SPREAD.describe()} or a table of "
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

    wind: Annotated[tuple[float, float, float], _vector(FORCE, "fx, fy, fz")] = (0.0, 0.0, 0.0)
    wind_model: Annotated[str | None, _text(_plugin_text("wind model"), optional=True)] = None
    gusts: Annotated[float, _number(GUSTS)] = 0.0
    spread: Annotated[Spread, BeforeValidator(_spread)] = Spread()


@dataclass(frozen=True, eq=False)
class MissionFiles:
    """What a mission reads from files besides its map: the vehicle and the controller's
    gains (:meth:`MissionConfig.load`; a batch loads them once for all its missions).

    Attributes:
        vehicle: the nominal vehicle.
        gains: the controller's own gains (None for a controller without gains).
    """

    vehicle: VehicleParams
    gains: Any


class MissionConfig(Section):
    """A whole mission (see the module docstring): what every command builds from.

    Attributes:
        map: a map file, a built-in world spec or a course map (``course:NAME``).
        seed: seeds the planner, the gusts and the vehicle spread.
        vehicle: a vehicle preset, a vehicle TOML file or spec, or a table of a vehicle's
            keys (as a vehicle file's, on top of ``based_on``, default ``tello``).
        query: start, goal and margin.
        planner: the path search.
        trajectory: the trajectory stage.
        controller: the controller and its gains.
        simulation: rates and settling.
        disturbances: wind, gusts and the vehicle spread.
    """

    map: FileOrName = DEFAULT_WORLD_SPEC
    seed: Annotated[int, _number(SEED)] = 0
    vehicle: TextOrTable = DEFAULT_PRESET
    query: Query = Query()
    planner: Planner = Planner()
    trajectory: Trajectory = Trajectory()
    controller: Controller = Controller()
    simulation: Simulation = Simulation()
    disturbances: Disturbances = Disturbances()

    _source: _Source | None = PrivateAttr(default=None)

    def __eq__(self, other: object) -> bool:
        """The same mission, wherever each was read from."""
        return isinstance(other, MissionConfig) and self.table() == other.table()

    def __hash__(self) -> int:
        return hash(repr(sorted(self.table().items())))

    @classmethod
    def from_table(cls, table: Mapping[str, Any], folder: str | Path | None = None,
                   source: str = "the mission") -> MissionConfig:
        """The mission a TOML-like ``table`` describes; relative paths are resolved against
        ``folder`` (None: left as they are). QuadnavError naming ``source`` and the key."""
        return _validated(dict(table), folder, _Source(source))

    def with_changes(self, changes: Mapping[str, Any],
                     names: Mapping[str, str] | None = None) -> MissionConfig:
        """This mission with the keys ``changes`` names (dotted, ``trajectory.speed``) set,
        checked again (e.g. the flags given on top of a mission file; ``names`` says how
        messages name each key set, e.g. ``--speed``). Setting ``query.start_goal``
        forgets a start and goal not also set, and another ``controller.name`` the gains
        of the controller it replaces (unless also set)."""
        table = self.table()
        if "query.start_goal" in changes:
            for key in ("start", "goal"):
                table.get("query", {}).pop(key, None)
        if changes.get("controller.name", self.controller.name) != self.controller.name:
            table.get("controller", {}).pop("gains", None)
        for dotted, value in changes.items():
            *parents, key = dotted.split(".")
            place = table
            for parent in parents:
                place = place.setdefault(parent, {})
            place[key] = value
        source = self._source or _Source("the mission")
        given = {key: (names or {}).get(key, key) for key in changes}
        return _validated(table, None, _Source(source.name, source.text,
                                               {**source.given, **given}))

    def table(self) -> dict[str, Any]:
        """The mission as a TOML-ready table, keys left unset (None) left out, a spread
        whose three fractions agree as one number."""
        table = self.model_dump(mode="json", exclude_none=True)
        spread = self.disturbances.spread
        if spread.mass == spread.thrust == spread.drag:
            table["disturbances"]["spread"] = spread.mass
        return table

    def toml(self, comment: str = "") -> str:
        """The mission as TOML text (:meth:`table`; lists of numbers on one line), after
        ``comment`` as ``#`` lines; :func:`read_mission` reads it back to the same
        mission."""
        import tomli_w

        lines = "".join(f"# {line}".rstrip() + "\n" for line in comment.splitlines())
        text = tomli_w.dumps(self.table())
        return lines + _NUMBER_LIST.sub(_one_line, text)

    # ---------------------------------------------------------------- building a mission
    def load(self) -> MissionFiles:
        """The vehicle and the controller's gains, read from their files (QuadnavError
        naming the mission file's line when one is bad)."""
        with self._keyed("vehicle"):
            vehicle = vehicle_from(self.vehicle, self._where("vehicle"))
        gains_key = "controller.gains" if self.controller.gains is not None else "controller.name"
        with self._keyed(gains_key):
            gains = controller_gains(self.controller.name, vehicle, self.controller.gains,
                                     self._where(gains_key))
        return MissionFiles(vehicle, gains)

    def world(self) -> World:
        """The map (QuadnavError naming the mission file's line when it cannot be read)."""
        with self._keyed("map"):
            return load_world(self.map)

    def settings(self, files: MissionFiles | None = None) -> MissionSettings:
        """The one builder of :class:`~quadnav.mission.MissionSettings`: every setting of
        this mission, with the vehicle and gains ``files`` (None: :meth:`load`); the flown
        vehicle (``plant``) is the nominal one scaled by :func:`spread_factors`.

        Raises:
            QuadnavError: settings that do not fit together (a physics rate that is not a
                multiple of the control rate, a control rate too slow for the gains).
        """
        files = files or self.load()
        fastest = self.trajectory.speed == MAX_SPEED
        with self._keyed(None):
            return MissionSettings(
                planner=self.planner.name,
                planning=PlannerSettings(time_limit=self.planner.time,
                                         max_iterations=self.planner.iterations or None,
                                         improve_iterations=self.planner.improve,
                                         seed=self.seed),
                refine=self.planner.refine,
                trajectory=TrajectorySettings(
                    method=self.trajectory.method, timing=self.trajectory.timing,
                    v_max=DEFAULT_SPEED if fastest else self.trajectory.speed,
                    a_max=self.trajectory.accel),
                fastest=fastest,
                vehicle=files.vehicle,
                gains=files.gains,
                controller=self.controller.name,
                reference=self.trajectory.reference,
                sim=SimSettings(physics_rate=self.simulation.physics_rate,
                                control_rate=self.simulation.control_rate,
                                record_rate=default_record_rate(self.simulation.control_rate),
                                settle_time=self.simulation.settle,
                                wind=self.disturbances.wind,
                                wind_model=self.disturbances.wind_model,
                                gust_std=self.disturbances.gusts, seed=self.seed),
                plant=spread_plant(files.vehicle, self.disturbances.spread, self.seed))

    def ends(self, world: World) -> tuple[np.ndarray | None, np.ndarray | None]:
        """The start and goal on ``world``, each (3,) m or None (none known): each one
        given, else the start/goal file's, else the map's own
        (:func:`~quadnav.world.startgoal.query_ends`)."""
        with self._keyed("query.start_goal"):
            return query_ends(world, self.query.start, self.query.goal,
                              self.query.start_goal)

    def margin(self, world: World) -> float:
        """The margin on ``world``, m: given, else the map's own, else 0.2
        (:meth:`~quadnav.world.World.margin_for`)."""
        return world.margin_for(self.query.margin)

    def problem(self, world: World, body: Any = (0.0, 0.0, 0.0)) -> PlanningProblem:
        """The checked query on ``world`` for a body of half extents ``body`` (3,) m
        (:func:`~quadnav.planning.make_problem`; QuadnavError for a bad one)."""
        start, goal = self.ends(world)
        return make_problem(world, start, goal, self.margin(world), body)

    def fly(self, planning_progress: Callable[[float, float], None] | None = None,
            flight_progress: Callable[[float], None] | None = None) -> Mission:
        """Load, check and fly the whole mission (:func:`~quadnav.mission.fly_problem`)."""
        settings = self.settings()
        problem = self.problem(self.world(), settings.body)
        return fly_problem(problem, settings, planning_progress, flight_progress)

    def flown(self, mission: Mission) -> MissionConfig:
        """What a run folder keeps of ``mission``, flown from this config, so that it flies
        again exactly wherever it is read: its start, goal and margin as flown (no
        start/goal file), a map file by its absolute path, the vehicle by its preset's
        name when it is a preset, else by its values, and the gains by their values when
        they are not the vehicle's own."""
        settings, problem = mission.settings, mission.problem
        vehicle: str | dict = _values(settings.vehicle)
        if settings.vehicle.name in preset_names() and vehicle == _values(
                load_params(settings.vehicle.name)):
            vehicle = settings.vehicle.name
        own = controller_gains(settings.controller, settings.vehicle)
        gains = None if _values(settings.gains) == _values(own) else _values(settings.gains)
        query = Query(start=tuple(problem.start), goal=tuple(problem.goal_asked),
                      margin=problem.margin)
        changes = {"map": os.path.abspath(self.map) if Path(self.map).is_file() else self.map,
                   "vehicle": vehicle, "query": query,
                   "controller": self.controller.model_copy(update={"gains": gains})}
        return self.model_copy(update=changes)

    # ------------------------------------------------------------------------ messages
    def _where(self, dotted: str) -> str:
        source = self._source or _Source("the mission")
        return source.where(dotted.split("."))

    @contextmanager
    def _keyed(self, dotted: str | None) -> Iterator[None]:
        """Name the mission file, and the line of ``dotted`` (None: the file alone), in a
        QuadnavError raised inside (one read from a file only)."""
        try:
            yield
        except QuadnavError as error:
            source = self._source
            if source is None or source.text is None or getattr(error, "details", None):
                raise
            where = source.name if dotted is None else self._where(dotted)
            message = str(error)
            raise QuadnavError(message if message.startswith(where) else
                               f"{where}: {message}") from None


def _values(config: Any) -> Any:
    """A config dataclass as a TOML-ready table (:func:`~quadnav.config.as_plain`), its
    keys that are None left out (TOML has no null; read back, they take their default)."""
    def kept(value: Any) -> Any:
        if isinstance(value, dict):
            return {key: kept(item) for key, item in value.items() if item is not None}
        return value
    return kept(as_plain(config))


def vehicle_from(vehicle: str | Mapping[str, Any], where: str = "vehicle") -> VehicleParams:
    """The vehicle a mission names: a preset, a vehicle TOML file or spec
    (:func:`~quadnav.vehicle.params.load_params`), or a table of a vehicle file's keys
    (:func:`~quadnav.vehicle.params.params_from_table`; ``where`` names it in messages)."""
    if isinstance(vehicle, str):
        return load_params(vehicle)
    return params_from_table(vehicle, where)


def spread_factors(spread: Spread, seed: int) -> tuple[float, float, float]:
    """The factors (mass, thrust coefficient, drag) of a mission's flown vehicle, each
    uniform in [1 - f, 1 + f] for its spread fraction f, drawn from the mission's seed."""
    rng = np.random.default_rng([seed, SPREAD_STREAM])
    draws = rng.uniform(-1.0, 1.0, 3)
    mass, thrust, drag = (1.0 + f * u for f, u in zip(
        (spread.mass, spread.thrust, spread.drag), draws, strict=True))
    return float(mass), float(thrust), float(drag)


def spread_plant(vehicle: VehicleParams, spread: Spread, seed: int) -> VehicleParams | None:
    """``vehicle`` scaled by :func:`spread_factors`, or None when no factor differs from 1."""
    mass, thrust, drag = spread_factors(spread, seed)
    if (mass, thrust, drag) == (1.0, 1.0, 1.0):
        return None
    return vehicle.replace(mass=vehicle.mass * mass,
                           thrust_coefficient=vehicle.thrust_coefficient * thrust,
                           drag=vehicle.drag * drag)


# ----------------------------------------------------------------------- mission files
def read_mission(path: str | Path) -> MissionConfig:
    """The mission in the TOML file ``path``; relative paths in it are resolved against its
    folder. QuadnavError, one line naming the file, the line and the key, for any mistake
    (files it names are read when the mission is built, naming the line too)."""
    path = Path(path)
    table = read_toml(path)
    source = _Source(str(path), path.read_text(encoding="utf-8"))
    return _validated(table, path.parent, source)


def _validated(table: dict[str, Any], folder: str | Path | None,
               source: _Source) -> MissionConfig:
    try:
        config = MissionConfig.model_validate(table, context={"folder": folder})
    except ValidationError as error:
        raise source.refusal(error.errors()[0]) from None
    config._source = source
    return config


def _section(path: list[str]) -> type[BaseModel]:
    """The schema of the table at ``path`` (its key names)."""
    model: type[BaseModel] = MissionConfig
    for key in path:
        field = model.model_fields.get(key)
        annotation = getattr(field, "annotation", None)
        if not (isinstance(annotation, type) and issubclass(annotation, BaseModel)):
            break
        model = annotation
    return model


#: A list of numbers as tomli-w writes it, an item per line.
_NUMBER_LIST = re.compile(r"\[\n((?:[ \t]+[-+0-9.eE]+,\n)+)\]")


def _one_line(match: re.Match) -> str:
    return "[" + ", ".join(item.strip().rstrip(",") for item in match.group(1).splitlines()) + "]"


_HEADER = re.compile(r"^\s*\[\s*([^\]\[]+?)\s*\]\s*(#.*)?$")
_KEY = re.compile(r"^\s*([A-Za-z0-9_.\"' -]+?)\s*=")


def _key_line(text: str, path: list[str]) -> int | None:
    """The 1-based line of ``text`` (TOML) that sets the key ``path``, else that of the
    deepest table of it that is set; None when neither is found."""
    best: tuple[int, int] | None = None  # (depth matched, line)
    table: list[str] = []
    for number, line in enumerate(text.splitlines(), start=1):
        header = _HEADER.match(line)
        if header:
            table = [part.strip().strip("\"'") for part in header.group(1).split(".")]
            found = table
        else:
            key = _KEY.match(line)
            if key is None:
                continue
            found = table + [part.strip().strip("\"'") for part in key.group(1).split(".")]
            inline = re.findall(r"[{,]\s*([A-Za-z0-9_]+)\s*=", line[key.end():])
            if len(found) < len(path) and path[len(found)] in inline:
                found = [*found, path[len(found)]]
        depth = len(found) if found == path[:len(found)] else 0
        if depth and (best is None or depth > best[0]):
            best = (depth, number)
    return None if best is None else best[1]
