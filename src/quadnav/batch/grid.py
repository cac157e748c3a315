"""What a batch flies: a :class:`BatchSpec` (read from a TOML spec or built from the command
line) and the :class:`MissionSpec` of each of its missions, enumerated in a fixed order.

A spec is a table (see the README's ``quadnav batch`` section)::

    seeds = 50                       # or a list [0, 1, 5], or {plan = 20, sim = 10}
    speeds = [1.0, 2.0]              # m/s, or "max"
    maps = ["forest", "map.json", {map = "map1.txt", start = [0.1, -4.9, 0.2], goal = [8, 18, 3]}]
    winds = [[0, 0, 0]]              # steady forces, N, or wind classes (grid; defaults)
    gusts = [0.0]                    # gust std, N
    spreads = [0.0]                  # vehicle spread fractions
    planners = ["rrtstar"]           # names or plug-in specs
    gains = ["default"]              # or gain files
    controllers = ["cascade"]        # names or plug-in specs
    methods = ["minsnap"]            # trajectory methods (or method = "minsnap")
    references = ["none"]            # "none" (the methods) or trajectory classes
    accel = 3.0                      # fixed settings, see FIXED_KEYS

Plug-ins are named as everywhere (:mod:`quadnav.plugins`): a registered name,
``module:Name`` or ``path/to/file.py:Name(key=value, ...)``, a file's path resolved here, so
that the spec string alone (it travels to every worker, on Ray too) names the plug-in.

Every value is checked against its stated range; every mistake is one
:class:`~quadnav.errors.QuadnavError` naming the spec and, where it can be found, the line.
Relative paths are resolved against the spec's folder. :meth:`BatchSpec.table` is the spec
with every path resolved and every default filled in: the batch folder keeps it
(``batch.json``), and :func:`spec_from_table` reads it back to the same spec.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
from collections.abc import Callable
from dataclasses import dataclass
from itertools import product
from pathlib import Path
from typing import Any

from quadnav.config import read_toml
from quadnav.control.gains import course_gain_names
from quadnav.control.registry import DEFAULT_CONTROLLER, controller_class
from quadnav.errors import MapError, QuadnavError
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
    STALL_FRACTION,
    Range,
    Speed,
    format_number,
    is_number,
    speed_value,
)
from quadnav.mission import DEFAULT_ACCELERATION, DEFAULT_IMPROVE
from quadnav.missionconfig import SPREAD_PARTS, Spread
from quadnav.missionconfig.checks import located
from quadnav.planning import get_planner
from quadnav.planning.stall import DEFAULT_STALL_FRACTION, DEFAULT_STALL_SAMPLES
from quadnav.plugins import PluginError
from quadnav.sim.settings import SimSettings
from quadnav.sim.wind import wind_maker
from quadnav.trajectory.generate import METHODS, TIMINGS
from quadnav.trajectory.references.plain import load_trajectory_class
from quadnav.vehicle.params import DEFAULT_PRESET, load_params, preset_names, vehicle_forms
from quadnav.world import read_start_goal
from quadnav.world.builtin import is_builtin_spec
from quadnav.world.courses import MAP, is_course_name, read_course_file

#: Wall-time cap of one mission's search, s: high enough that the sample rules
#: (``stall``, ``improve``) end every search in practice, so a mission's row depends on
#: its seed alone.
DEFAULT_TIME_CAP = 60.0
#: The most missions one batch may hold.
MAX_MISSIONS = 1_000_000
#: Seeds a batch may draw (``seeds = N`` for seeds 0 to N - 1).
SEED_COUNT = Range(1, MAX_MISSIONS, whole=True)
#: The gains of the vehicle, as a ``gains`` entry.
DEFAULT_GAINS = "default"
#: The trajectory method of a batch that names none.
DEFAULT_METHOD = "minsnap"
#: A ``references`` entry: no trajectory class of your own, but the trajectory stage with
#: each of the batch's methods.
NO_REFERENCE = "none"

#: Keys of the grid, each a list of values.
GRID_KEYS = ("maps", "seeds", "speeds", "winds", "gusts", "spreads", "planners", "gains",
             "controllers", "methods", "references")
#: A key that sets one trajectory method, as ``methods = [...]`` with one (a batch's
#: spec before methods became a list of the grid).
METHOD_KEY = "method"
#: Keys of a ``seeds`` table: the planner's seeds and the simulation's, each a count or a
#: list.
SEED_KEYS = ("plan", "sim")
#: Keys of a map entry given as a table.
MAP_KEYS = ("map", "start", "goal", "start_goal", "margin")


@dataclass(frozen=True)
class FixedSettings:
    """Settings that every mission of a batch shares.

    Attributes:
        accel: largest acceleration of the trajectories, m/s^2.
        margin: safety margin of maps without their own, m (None: the map's, else 0.2).
        vehicle: a vehicle preset name, a TOML file (resolved path) or a rotorpy dict
            (``module:NAME`` or ``file.py:NAME``, its file resolved).
        settle: time flown after each trajectory ends, s.
        timing: segment timing (:data:`~quadnav.trajectory.generate.TIMINGS`).
        improve: samples of improvement after a search's first path, at most.
        stall: a search stops once its best length has shortened by at most
            ``stall_fraction`` over this many samples (:mod:`quadnav.planning.stall`); 0:
            no such rule, a fixed budget.
        stall_fraction: that fraction of the best length.
        time_cap: wall-time cap of a search, s.
        physics_rate: RK4 steps per second, Hz.
        control_rate: controller updates per second, Hz.
    """

    accel: float = DEFAULT_ACCELERATION
    margin: float | None = None
    vehicle: str = DEFAULT_PRESET
    settle: float = SimSettings.settle_time
    timing: str = "fastest"
    improve: int = DEFAULT_IMPROVE
    stall: int = DEFAULT_STALL_SAMPLES
    stall_fraction: float = DEFAULT_STALL_FRACTION
    time_cap: float = DEFAULT_TIME_CAP
    physics_rate: float = SimSettings.physics_rate
    control_rate: float = SimSettings.control_rate


#: Keys of the fixed settings.
FIXED_KEYS = tuple(FixedSettings.__dataclass_fields__)
ALL_KEYS = (*GRID_KEYS, METHOD_KEY, *FIXED_KEYS)


@dataclass(frozen=True)
class MapEntry:
    """One map of the grid with its query.

    Attributes:
        map: a map file (resolved path), a built-in world spec or a course map (``course:NAME``).
        start: (x, y, z) m, or None: the map's own, else drawn from each mission's seed.
        goal: likewise.
        margin: m, or None: the batch's ``margin``, else the map's own, else 0.2.
    """

    map: str
    start: tuple[float, float, float] | None = None
    goal: tuple[float, float, float] | None = None
    margin: float | None = None


#: A wind of the grid: a steady force (3,) N, world frame, or a wind class's spec.
Wind = tuple[float, float, float] | str


@dataclass(frozen=True)
class MissionSpec:
    """One mission of a batch: everything its row depends on besides the fixed settings.

    Attributes:
        map: the map and its query.
        seed: seed of the planner and a drawn start/goal, and unless ``sim_seed`` is
            given of the gusts and the spread factors.
        speed: top speed, m/s, or ``"max"``: as fast as the vehicle can follow.
        wind: (3,) steady force, N, world frame, or a wind class's spec.
        gusts: gust standard deviation per axis, N.
        spread: the vehicle spread.
        planner: planner name or spec.
        gains: ``default`` or a gains file (resolved path).
        controller: controller name or spec.
        method: the trajectory method, or None when ``reference`` replaces the trajectory
            stage.
        reference: a trajectory class's spec flown instead of a method's trajectory, or
            None.
        sim_seed: seed of the gusts and the spread factors alone (a spec's
            ``seeds = {plan = ..., sim = ...}``); None: ``seed`` seeds them.
    """

    map: MapEntry
    seed: int
    speed: Speed
    wind: Wind
    gusts: float
    spread: Spread
    planner: str
    gains: str
    controller: str = DEFAULT_CONTROLLER
    method: str | None = DEFAULT_METHOD
    reference: str | None = None
    sim_seed: int | None = None

    @property
    def flight_seed(self) -> int:
        """The seed of the gusts and the spread factors: ``sim_seed``, else ``seed``."""
        return self.seed if self.sim_seed is None else self.sim_seed

    @property
    def key(self) -> str:
        """A short stable name of the mission: a hash of its grid values. A mission that
        flies the default controller and method with one seed has the key it had before
        batches could vary them (:attr:`earlier_key`), so a batch folder written then
        resumes."""
        chosen = {"controller": self.controller, "method": self.method,
                  "reference": self.reference, "sim_seed": self.sim_seed}
        defaults = {"controller": DEFAULT_CONTROLLER, "method": DEFAULT_METHOD,
                    "reference": None, "sim_seed": None}
        changed = {name: value for name, value in chosen.items() if value != defaults[name]}
        return self._hash([changed] if changed else [])

    @property
    def earlier_key(self) -> str:
        """The key a batch folder written before controllers, methods and references were
        values of the grid gave this mission (then flown with the default controller and
        the batch's one method)."""
        return self._hash([])

    def _hash(self, extra: list) -> str:
        speed = None if self.speed == MAX_SPEED else self.speed  # as keys were made before
        values = json.dumps([self.map.__dict__, self.seed, speed, self.wind, self.gusts,
                             self.spread.__dict__, self.planner, self.gains, *extra],
                            sort_keys=True)
        return hashlib.sha256(values.encode()).hexdigest()[:16]


@dataclass(frozen=True)
class BatchSpec:
    """The grid and the fixed settings of a batch (see the module docstring): ``seeds``
    seed the planner and, when ``sim_seeds`` is None, the simulation too; else each seed
    of ``seeds`` is flown with each of ``sim_seeds``."""

    maps: tuple[MapEntry, ...]
    seeds: tuple[int, ...]
    speeds: tuple[Speed, ...]
    winds: tuple[Wind, ...]
    gusts: tuple[float, ...]
    spreads: tuple[Spread, ...]
    planners: tuple[str, ...]
    gains: tuple[str, ...]
    fixed: FixedSettings
    controllers: tuple[str, ...] = (DEFAULT_CONTROLLER,)
    methods: tuple[str, ...] = (DEFAULT_METHOD,)
    references: tuple[str, ...] = (NO_REFERENCE,)
    sim_seeds: tuple[int, ...] | None = None

    @property
    def seed_pairs(self) -> list[tuple[int, int | None]]:
        """Each mission's (seed, sim_seed), in the grid's order: every seed with every
        simulation seed, or each seed alone (None) when one seed drives both."""
        return list(product(self.seeds, self.sim_seeds or [None]))

    @property
    def flight_seeds(self) -> tuple[int, ...]:
        """The seeds of the simulations (the gusts, the spread): ``sim_seeds``, else
        ``seeds``."""
        return self.seeds if self.sim_seeds is None else self.sim_seeds

    @property
    def trajectories(self) -> list[tuple[str | None, str | None]]:
        """What makes each mission's reference, as (method, reference) pairs, in the order
        of :attr:`references`: ``none`` stands for every method (with no reference), any
        other entry for its trajectory class (with no method)."""
        return [pair for reference in self.references for pair in (
            [(method, None) for method in self.methods] if reference == NO_REFERENCE
            else [(None, reference)])]

    @property
    def contender_keys(self) -> list[str]:
        """The lists of contenders that hold more than one: of ``controllers``,
        ``planners``, ``methods`` with ``references`` (as ``references``), ``winds`` and
        ``gains``."""
        lists = {"controllers": self.controllers, "planners": self.planners,
                 "references": self.trajectories, "winds": self.winds, "gains": self.gains}
        return [key for key, values in lists.items() if len(values) > 1]

    def missions(self) -> list[MissionSpec]:
        """Every mission, in a fixed order: map, speed, wind, gusts, spread, planner,
        gains, controller, trajectory, then seed, then simulation seed (innermost)."""
        return [MissionSpec(m, seed, speed, wind, gust, spread, planner, gains, controller,
                            method, reference, sim_seed)
                for m, speed, wind, gust, spread, planner, gains, controller,
                (method, reference), (seed, sim_seed) in product(
                    self.maps, self.speeds, self.winds, self.gusts, self.spreads,
                    self.planners, self.gains, self.controllers, self.trajectories,
                    self.seed_pairs)]

    @property
    def size(self) -> int:
        """Number of missions."""
        return math.prod(len(values) for values in (
            self.maps, self.seed_pairs, self.speeds, self.winds, self.gusts, self.spreads,
            self.planners, self.gains, self.controllers, self.trajectories))

    def table(self) -> dict[str, Any]:
        """The spec as a TOML-like table with every path resolved and every default filled
        in (but the methods when no mission flies one); :func:`spec_from_table` reads it
        back to this spec."""
        methods = {"methods": list(self.methods)} if NO_REFERENCE in self.references else {}
        maps = [{key: list(value) if isinstance(value, tuple) else value
                 for key, value in entry.__dict__.items() if value is not None}
                for entry in self.maps]
        seeds: list | dict = list(self.seeds)
        if self.sim_seeds is not None:
            seeds = {"plan": seeds, "sim": list(self.sim_seeds)}
        return {
            "maps": maps, "seeds": seeds,
            "speeds": list(self.speeds),
            "winds": [w if isinstance(w, str) else list(w) for w in self.winds],
            "gusts": list(self.gusts),
            "spreads": [s.__dict__ for s in self.spreads], "planners": list(self.planners),
            "gains": list(self.gains), "controllers": list(self.controllers),
            "references": list(self.references),
        } | methods | {key: value for key, value in self.fixed.__dict__.items()
                       if value is not None}


class _Source:
    """Where a spec comes from, for messages: the file and its text (to find lines)."""

    def __init__(self, name: str, text: str = "") -> None:
        self.name = name
        self.text = text

    def error(self, key: str, message: str) -> QuadnavError:
        """A one-line error about ``key``, naming the line that sets it if one does."""
        match = re.search(rf"^\s*\[?\s*{re.escape(key)}\s*[=\]]", self.text, re.MULTILINE)
        if match is None:
            match = re.search(rf"[{{,]\s*{re.escape(key)}\s*=", self.text)
        where = self.name
        if match is not None:
            where += f":{self.text.count(chr(10), 0, match.start() + 1) + 1}"
        return QuadnavError(f"{where}: {key}: {message}")


def read_spec(path: str | Path) -> BatchSpec:
    """The spec in the TOML file at ``path``; relative paths in it are resolved against its
    folder. QuadnavError (one line naming the file and line) for any mistake."""
    path = Path(path)
    table = read_toml(path)
    return spec_from_table(table, path.parent,
                           _Source(str(path), path.read_text(encoding="utf-8")))


def spec_from_table(table: dict[str, Any], folder: str | Path,
                    source: _Source | str = "the batch spec") -> BatchSpec:
    """A spec from a TOML-like ``table``; relative paths are resolved against ``folder``."""
    src = source if isinstance(source, _Source) else _Source(source)
    folder = Path(folder)
    for key in table:
        if key not in ALL_KEYS:
            raise src.error(key, f"unknown key; expected one of {', '.join(ALL_KEYS)}")
    for key in ("maps", "seeds", "speeds"):
        if key not in table:
            raise QuadnavError(f"{src.name}: missing key {key!r}: a batch needs maps, seeds "
                               "and speeds")
    fixed = _fixed(table, folder, src)
    seeds, sim_seeds = _seed_lists(table["seeds"], src)
    spec = BatchSpec(
        maps=tuple(_map_entry(item, folder, src) for item in _list(table, "maps", src)),
        seeds=seeds,
        speeds=tuple(_speed(value, src) for value in _list(table, "speeds", src)),
        winds=tuple(_wind(value, folder, src)
                    for value in _list(table, "winds", src, [[0, 0, 0]])),
        gusts=tuple(_number(value, GUSTS, "gusts", src)
                    for value in _list(table, "gusts", src, [0.0])),
        spreads=tuple(_spread(value, src) for value in _list(table, "spreads", src, [0.0])),
        planners=tuple(_plugin(value, folder, "planners", get_planner, src)
                       for value in _list(table, "planners", src, ["rrtstar"])),
        gains=tuple(_gains(value, folder, src)
                    for value in _list(table, "gains", src, [DEFAULT_GAINS])),
        fixed=fixed,
        controllers=tuple(_plugin(value, folder, "controllers", controller_class, src)
                          for value in _list(table, "controllers", src,
                                             [DEFAULT_CONTROLLER])),
        methods=_methods(table, src),
        references=tuple(_reference(value, folder, src)
                         for value in _list(table, "references", src, [NO_REFERENCE])),
        sim_seeds=sim_seeds)
    if NO_REFERENCE not in spec.references and (
            "methods" in table or METHOD_KEY in table):
        key = "methods" if "methods" in table else METHOD_KEY
        raise src.error(key, f"no mission flies a method: every reference is a trajectory "
                             f"class of your own (add {NO_REFERENCE!r} to references to fly "
                             "the methods too)")
    if spec.size > MAX_MISSIONS:
        raise QuadnavError(f"{src.name}: the grid holds {format_number(spec.size)} missions; "
                           f"expected at most {format_number(MAX_MISSIONS)}")
    return spec


def _list(table: dict, key: str, src: _Source, default: list | None = None) -> list:
    """The non-empty list at ``key`` (a single value counts as a list of one)."""
    value = table.get(key, default)
    values = value if isinstance(value, list) else [value]
    if not values:
        raise src.error(key, "expected at least one value, got an empty list")
    if len(values) != len({json.dumps(v, sort_keys=True) for v in values}):
        raise src.error(key, "a value is listed twice")
    return values


def _number(value: Any, allowed: Range, key: str, src: _Source) -> float:
    if not is_number(value) or value not in allowed:
        raise src.error(key, f"expected {allowed.describe()}, got {value!r}")
    return int(value) if allowed.whole else float(value)


def _point(value: Any, key: str, src: _Source) -> tuple[float, float, float]:
    if not (isinstance(value, list) and len(value) == 3
            and all(is_number(v) and v in COORDINATE for v in value)):
        raise src.error(key, f"expected [x, y, z], each {COORDINATE.describe()}, got {value!r}")
    x, y, z = (float(v) for v in value)
    return x, y, z


def _seed_lists(value: Any, src: _Source) -> tuple[tuple[int, ...], tuple[int, ...] | None]:
    """The seeds of the planner and of the simulation (None: the planner's seed them
    too): a count or a list for both, or a table ``{plan = ..., sim = ...}`` of two."""
    if not isinstance(value, dict):
        return _seeds(value, src), None
    for key in value:
        if key not in SEED_KEYS:
            raise src.error("seeds", f"unknown key {key!r} in a seeds table; expected "
                                     f"{' and '.join(SEED_KEYS)}")
    missing = [key for key in SEED_KEYS if key not in value]
    if missing:
        raise src.error("seeds", f"a seeds table needs {' and '.join(SEED_KEYS)}, each a "
                                 f"count or a list; {missing[0]} is missing")
    return _seeds(value["plan"], src, "plan: "), _seeds(value["sim"], src, "sim: ")


def _seeds(value: Any, src: _Source, part: str = "") -> tuple[int, ...]:
    """Seeds 0 to N - 1 for a count N, or a list of seeds; ``part`` begins each message
    (``plan: `` for a seeds table's ``plan``)."""
    if not isinstance(value, list):
        return tuple(range(int(_seed(value, SEED_COUNT, src, part))))
    if not value:
        raise src.error("seeds", f"{part}expected at least one value, got an empty list")
    if len(value) != len({json.dumps(v) for v in value}):
        raise src.error("seeds", f"{part}a value is listed twice")
    return tuple(_seed(v, SEED, src, part) for v in value)


def _seed(value: Any, allowed: Range, src: _Source, part: str) -> int:
    """One seed, or a count of seeds, in ``allowed``."""
    if not is_number(value) or value not in allowed:
        raise src.error("seeds", f"{part}expected {allowed.describe()}, got {value!r}")
    return int(value)


def _speed(value: Any, src: _Source) -> Speed:
    speed = speed_value(value)
    if speed is None:
        raise src.error("speeds", f"expected {SPEED.describe()} or \"max\", got {value!r}")
    return speed


def _wind(value: Any, folder: Path, src: _Source) -> Wind:
    if isinstance(value, str):
        return _plugin(value, folder, "winds", wind_maker, src)
    if not (isinstance(value, list) and len(value) == 3
            and all(is_number(v) and v in FORCE for v in value)):
        raise src.error("winds", f"expected [fx, fy, fz] forces, each {FORCE.describe()}, "
                                 f"or a wind class (module:Class or file.py:Class), got "
                                 f"{value!r}")
    x, y, z = (float(v) for v in value)
    return x, y, z


def _spread(value: Any, src: _Source) -> Spread:
    if isinstance(value, dict):
        for part in value:
            if part not in SPREAD_PARTS:
                raise src.error(part, f"unknown key in a spread; expected one of "
                                      f"{', '.join(SPREAD_PARTS)}")
        return Spread(**{part: _number(f, SPREAD, "spreads", src) for part, f in value.items()})
    return Spread(**dict.fromkeys(SPREAD_PARTS, _number(value, SPREAD, "spreads", src)))


def _plugin(value: Any, folder: Path, key: str, check: Callable[[str], object],
            src: _Source) -> str:
    """A name or plug-in spec of the list ``key``, the path of a file in it
    (``path/to/file.py:Name``) resolved against ``folder``
    (:func:`~quadnav.missionconfig.checks.located`), loaded and checked by
    ``check`` (QuadnavError for a bad one, naming the spec's line; a plug-in's own
    traceback kept)."""
    if not isinstance(value, str) or not value.strip():
        raise src.error(key, f"expected a name or module:NAME or file.py:NAME, got {value!r}")
    if value.partition(":")[0].endswith(".py"):
        value = located(value, folder)
    try:
        check(value)
    except QuadnavError as error:
        raise _located_error(src, key, error) from None
    return value


def _located_error(src: _Source, key: str, error: QuadnavError) -> QuadnavError:
    """``error`` as one line naming ``key``'s line; a plug-in's own traceback kept."""
    located_error = src.error(key, str(error))
    if isinstance(error, PluginError):
        return PluginError(str(located_error), error.details, error.exit_code)
    return located_error


def _methods(table: dict, src: _Source) -> tuple[str, ...]:
    """The trajectory methods: ``methods``, or the one of ``method``."""
    if "methods" in table and METHOD_KEY in table:
        raise src.error(METHOD_KEY, "give methods (a list) or method (one), not both")
    key = METHOD_KEY if METHOD_KEY in table else "methods"
    return tuple(_choice(value, tuple(METHODS.names()), key, src)
                 for value in _list(table, key, src, [DEFAULT_METHOD]))


def _reference(value: Any, folder: Path, src: _Source) -> str:
    """``none`` or a trajectory class built from each mission's path."""
    if value == NO_REFERENCE:
        return value
    return _plugin(value, folder, "references",
                   lambda text: load_trajectory_class(text, with_points=True), src)


def _file(value: Any, folder: Path, key: str, what: str, src: _Source) -> str:
    """``value`` as a path resolved against ``folder``; it must be a file."""
    if not isinstance(value, str):
        raise src.error(key, f"expected {what}, got {value!r}")
    path = Path(value).expanduser()
    path = path if path.is_absolute() else folder / path
    if not path.is_file():
        raise src.error(key, f"expected {what}, got {value!r} (no such file: {path})")
    return os.path.abspath(path)


def _gains(value: Any, folder: Path, src: _Source) -> str:
    if value == DEFAULT_GAINS or value in course_gain_names():
        return value
    return _file(value, folder, "gains", f"{DEFAULT_GAINS!r}, a course gain table "
                 f"({', '.join(course_gain_names())}) or a gains TOML file", src)


def _named(value: Any, folder: Path, is_name: Callable[[str], bool]) -> bool:
    """Whether ``value`` is a name ``is_name`` knows (a course file, a built-in world
    spec) that no file in the spec's ``folder`` has."""
    return isinstance(value, str) and is_name(value) and not (folder / value).is_file()


def _vehicle(value: Any, folder: Path, src: _Source) -> str:
    """A vehicle preset, a TOML file (resolved), or a rotorpy dict named ``module:NAME`` or
    ``file.py:NAME`` (the file resolved; checked here, before any mission flies)."""
    if value in preset_names():
        return value
    if _named(value, folder, lambda text: ":" in text):
        where, _, name = value.partition(":")
        if where.endswith(".py"):
            value = f"{os.path.abspath(folder / Path(where).expanduser())}:{name}"
        try:
            load_params(value)
        except QuadnavError as error:
            raise _located_error(src, "vehicle", error) from None
        return value
    return _file(value, folder, "vehicle", vehicle_forms(), src)


def _map_name(value: Any, folder: Path, key: str, src: _Source) -> str:
    """A map file (resolved), a built-in world spec, or a course map (``course:NAME``,
    shipped or fetched: checked here, before any mission flies)."""
    if _named(value, folder, is_course_name):
        try:
            read_course_file(value, MAP)
        except MapError as error:
            raise src.error(key, str(error)) from None
        return value
    if _named(value, folder, is_builtin_spec):
        return value
    return _file(value, folder, key, "a map file, a built-in world spec or a course map "
                 "(course:NAME)", src)


def _map_entry(item: Any, folder: Path, src: _Source) -> MapEntry:
    if not isinstance(item, dict):
        return MapEntry(_map_name(item, folder, "maps", src))
    for key in item:
        if key not in MAP_KEYS:
            raise src.error(key, f"unknown key in a map entry; expected one of "
                                 f"{', '.join(MAP_KEYS)}")
    if "map" not in item:
        raise src.error("maps", f"a map entry needs a map: {item!r}")
    start = goal = None
    if "start_goal" in item:
        start, goal = (tuple(float(v) for v in point) for point in
                       _start_goal(item["start_goal"], folder, src))
    if "start" in item:
        start = _point(item["start"], "start", src)
    if "goal" in item:
        goal = _point(item["goal"], "goal", src)
    margin = item.get("margin")
    return MapEntry(_map_name(item["map"], folder, "map", src), start, goal,
                    None if margin is None else _number(margin, MARGIN, "margin", src))


def _start_goal(value: Any, folder: Path, src: _Source) -> tuple:
    """(start, goal) from a start/goal file (resolved) or a course one (``course:NAME``)."""
    if _named(value, folder, is_course_name):
        try:
            return read_start_goal(value)
        except MapError as error:
            raise src.error("start_goal", str(error)) from None
    return read_start_goal(_file(value, folder, "start_goal", "a start/goal file or a course "
                                 "one (course:NAME)", src))


def _choice(value: Any, choices: tuple[str, ...], key: str, src: _Source) -> str:
    if value not in choices:
        raise src.error(key, f"expected one of {', '.join(choices)}, got {value!r}")
    return value


def _fixed(table: dict, folder: Path, src: _Source) -> FixedSettings:
    """The fixed settings of ``table``, defaults for those it leaves out."""
    base = FixedSettings()
    checks = {"accel": ACCELERATION, "margin": MARGIN, "settle": SETTLE,
              "improve": SAMPLES, "stall": SAMPLES, "stall_fraction": STALL_FRACTION,
              "time_cap": PLAN_TIME,
              "physics_rate": RATE, "control_rate": RATE}
    values = {key: _number(table[key], allowed, key, src)
              for key, allowed in checks.items() if key in table}
    if "timing" in table:
        values["timing"] = _choice(table["timing"], TIMINGS, "timing", src)
    values["vehicle"] = _vehicle(table.get("vehicle", base.vehicle), folder, src)
    return FixedSettings(**{**base.__dict__, **values})
