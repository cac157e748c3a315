"""A whole mission: :class:`MissionConfig`, the one builder of the pipeline's settings
(:meth:`MissionConfig.settings`) and of its query (:meth:`MissionConfig.problem`), and
:func:`read_mission` (see the package's description)."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from pydantic import PrivateAttr, ValidationError

from quadnav.config import as_plain, read_toml, toml_text
from quadnav.control.registry import controller_gains
from quadnav.errors import QuadnavError
from quadnav.limits import MAX_SPEED, SEED
from quadnav.mission import DEFAULT_SPEED, Mission, MissionSettings, fly_problem
from quadnav.missionconfig.checks import FileOrName, TextOrTable, located, number
from quadnav.missionconfig.sections import (
    Controller,
    Disturbances,
    Planner,
    Query,
    Section,
    Simulation,
    Spread,
    Trajectory,
)
from quadnav.missionconfig.source import Source
from quadnav.planning import PlannerSettings, PlanningProblem, Progress, make_problem
from quadnav.planning.stall import stall_rule
from quadnav.sim.settings import SimSettings, default_record_rate
from quadnav.trajectory.generate import TrajectorySettings
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


@dataclass(frozen=True, eq=False)
class MissionFiles:
    """What a mission reads from files besides its map: the vehicle and the controller's
    gains (:meth:`MissionConfig.load`; a batch loads them once for all its missions).

    Attributes:
        vehicle: the nominal vehicle.
        gains: the controller's gains as given, or None: those tuned for the vehicle
            (:attr:`~quadnav.mission.MissionSettings.flown_gains`).
    """

    vehicle: VehicleParams
    gains: Any


class MissionConfig(Section):
    """A whole mission (see :mod:`quadnav.missionconfig`): what every command builds from.

    Attributes:
        map: a map file, a built-in world spec or a course map (``course:NAME``).
        seed: seeds the planner, a batch's drawn start and goal, and (unless
            ``simulation.seed`` is set) the gusts and the vehicle spread.
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
    seed: Annotated[int, number(SEED)] = 0
    vehicle: TextOrTable = DEFAULT_PRESET
    query: Query = Query()
    planner: Planner = Planner()
    trajectory: Trajectory = Trajectory()
    controller: Controller = Controller()
    simulation: Simulation = Simulation()
    disturbances: Disturbances = Disturbances()

    _source: Source | None = PrivateAttr(default=None)

    def __eq__(self, other: object) -> bool:
        """The same mission, wherever each was read from."""
        return isinstance(other, MissionConfig) and self.table() == other.table()

    def __hash__(self) -> int:
        """The hash of :meth:`table`, as equality compares it."""
        return hash(repr(sorted(self.table().items())))

    @classmethod
    def from_table(cls, table: Mapping[str, Any], folder: str | Path | None = None,
                   source: str = "the mission") -> MissionConfig:
        """The mission a TOML-like ``table`` describes; relative paths are resolved against
        ``folder`` (None: left as they are). QuadnavError naming ``source`` and the key."""
        return _validated(dict(table), folder, Source(source))

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
        source = self._source or Source("the mission")
        given = {key: (names or {}).get(key, key) for key in changes}
        return _validated(table, None, Source(source.name, source.text,
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
        return toml_text(self.table(), comment)

    # ---------------------------------------------------------------- building a mission
    def load(self) -> MissionFiles:
        """The vehicle and the controller's gains, read from their files (QuadnavError
        naming the mission file's line when one is bad)."""
        with self._keyed("vehicle"):
            vehicle = vehicle_from(self.vehicle, self._where("vehicle"))
        given = self.controller.gains
        gains_key = "controller.name" if given is None else "controller.gains"
        with self._keyed(gains_key):  # checked here, for the line: the vehicle's own too
            gains = controller_gains(self.controller.name, vehicle, given,
                                     self._where(gains_key))
        return MissionFiles(vehicle, None if given is None else gains)

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
                                         stall=stall_rule(self.planner.stall,
                                                          self.planner.stall_fraction),
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
                reference_duration=self.trajectory.duration,
                sim=SimSettings(physics_rate=self.simulation.physics_rate,
                                control_rate=self.simulation.control_rate,
                                record_rate=default_record_rate(self.simulation.control_rate),
                                settle_time=self.simulation.settle,
                                wind=self.disturbances.wind,
                                wind_model=self.disturbances.wind_model,
                                gust_std=self.disturbances.gusts, seed=self.flight_seed),
                plant=spread_plant(files.vehicle, self.disturbances.spread, self.flight_seed))

    @property
    def flight_seed(self) -> int:
        """The seed of the gusts and the vehicle spread: ``simulation.seed``, else the
        mission's."""
        return self.seed if self.simulation.seed is None else self.simulation.seed

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

    def fly(self, planning_progress: Progress | None = None,
            flight_progress: Callable[[float], None] | None = None) -> Mission:
        """Load, check and fly the whole mission (:func:`~quadnav.mission.fly_problem`)."""
        settings = self.settings()
        problem = self.problem(self.world(), settings.body)
        return fly_problem(problem, settings, planning_progress, flight_progress)

    def flown(self, mission: Mission) -> MissionConfig:
        """What a run folder keeps of ``mission``, flown from this config, so that it flies
        again exactly wherever it is read: its start, goal and margin as flown (no
        start/goal file), a map file and the plug-ins in files (planner, controller,
        reference, wind model) by their absolute paths, the vehicle by its preset's name
        when it is a preset, else by its values (a vehicle file's or a rotorpy dict's: the
        vehicle as flown, whatever becomes of the file or the package it came from), and
        the gains by their values when they are not the vehicle's own."""
        settings, problem = mission.settings, mission.problem
        vehicle: str | dict = _values(settings.vehicle)
        if settings.vehicle.name in preset_names() and vehicle == _values(
                load_params(settings.vehicle.name)):
            vehicle = settings.vehicle.name
        own = controller_gains(settings.controller, settings.vehicle)
        flown = _values(settings.flown_gains)
        gains = None if flown == _values(own) else flown
        query = Query(start=tuple(problem.start), goal=tuple(problem.goal_asked),
                      margin=problem.margin)
        here = os.getcwd()

        def plugin(text: str | None) -> str | None:
            return None if text is None else located(text, here)

        changes = {
            "map": located(self.map, here), "vehicle": vehicle, "query": query,
            "planner": self.planner.model_copy(update={"name": plugin(self.planner.name)}),
            "trajectory": self.trajectory.model_copy(
                update={"reference": plugin(self.trajectory.reference)}),
            "controller": self.controller.model_copy(
                update={"name": plugin(self.controller.name), "gains": gains}),
            "disturbances": self.disturbances.model_copy(
                update={"wind_model": plugin(self.disturbances.wind_model)})}
        return self.model_copy(update=changes)

    # ------------------------------------------------------------------------ messages
    def _where(self, dotted: str) -> str:
        source = self._source or Source("the mission")
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
    """``vehicle`` scaled by :func:`spread_factors` (the drag factor scales its linear,
    rotor and parasitic drag alike), or None when no factor differs from 1."""
    mass, thrust, drag = spread_factors(spread, seed)
    if (mass, thrust, drag) == (1.0, 1.0, 1.0):
        return None
    return vehicle.replace(mass=vehicle.mass * mass,
                           thrust_coefficient=vehicle.thrust_coefficient * thrust,
                           drag=vehicle.drag * drag, rotor_drag=vehicle.rotor_drag * drag,
                           parasitic_drag=vehicle.parasitic_drag * drag)


# ----------------------------------------------------------------------- mission files
def read_mission(path: str | Path) -> MissionConfig:
    """The mission in the TOML file ``path``; relative paths in it are resolved against its
    folder. QuadnavError, one line naming the file, the line and the key, for any mistake
    (files it names are read when the mission is built, naming the line too)."""
    path = Path(path)
    table = read_toml(path)
    source = Source(str(path), path.read_text(encoding="utf-8"))
    return _validated(table, path.parent, source)


def read_run_mission(path: str | Path) -> MissionConfig:
    """The mission a run folder keeps in ``path`` (:func:`read_mission`), as it flew: one
    written before the stall rule (its ``[planner]`` names ``improve`` but no ``stall``, as
    every run folder's names all its keys) searched for its whole ``improve`` budget, so it
    flies again with ``stall = 0``."""
    config = read_mission(path)
    given = config.planner.model_fields_set
    if "improve" in given and "stall" not in given:
        return config.with_changes({"planner.stall": 0})
    return config


def _validated(table: dict[str, Any], folder: str | Path | None,
               source: Source) -> MissionConfig:
    try:
        config = MissionConfig.model_validate(table, context={"folder": folder})
    except ValidationError as error:
        raise source.refusal(error.errors()[0], MissionConfig) from None
    config._source = source
    return config
