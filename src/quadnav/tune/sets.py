"""What ``quadnav tune`` flies to score gains: a :class:`TuneSet` of references and missions,
turned into :class:`TuneItem`\\ s, each a reference flown in its world.

A set is a TOML table: the keys of a batch spec (:mod:`quadnav.batch.grid`: ``maps``,
``seeds``, ``speeds``, ``winds``, ``gusts``, ``spreads``, ``planners`` and the fixed
settings) for its missions, plus ``references``, built-in reference specs or reference
files (:func:`~quadnav.trajectory.references.builtin.load_reference`), flown once per seed, wind
and gust level::

    references = ["hover:duration=4", "step:axis=x", "helix:speed=1.5,laps=2"]
    maps = ["forest", "window"]
    seeds = [0, 1]
    speeds = [2.0]
    gusts = [0.01]

A mission is planned once, with the starting gains, and its trajectory kept: tuning
changes how it is flown, not what is flown. Missions that share a plan or a trajectory
(another wind, gust level or spread, another simulation seed) make it once
(:class:`~quadnav.batch.stages.StageCache`). The shipped sets (:data:`SHIPPED_SETS`) are a
training set and a held-out set of different references, maps and seeds.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from importlib import resources
from itertools import product
from pathlib import Path
from typing import Any

from quadnav.batch.fly_one import BatchContext, load_context, mission_problem, mission_settings
from quadnav.batch.grid import BatchSpec, MissionSpec, spec_from_table
from quadnav.batch.stages import StageCache
from quadnav.config import read_toml
from quadnav.control.gains import Gains
from quadnav.errors import PlanningWarning, QuadnavError
from quadnav.limits import speed_text
from quadnav.sim.settings import SimSettings
from quadnav.tracking import track_world
from quadnav.trajectory.references.builtin import StepReference, load_reference
from quadnav.trajectory.references.contract import Reference
from quadnav.vehicle.params import VehicleParams
from quadnav.world.model import World

#: The sets shipped with quadnav, by name: ``training`` and ``held-out``.
SHIPPED_SETS = ("training", "held-out")
#: Keys of a set besides a batch spec's.
REFERENCE_KEYS = ("references",)


@dataclass(frozen=True, eq=False)
class TuneItem:
    """One flight of a set, flown again for every trial.

    Attributes:
        name: how reports name it, e.g. ``step:axis=x,... seed 0`` or ``forest ... 2 m/s``.
        reference: what is flown.
        world: the real map of a mission, the empty world around a reference.
        settings: the simulation settings (seed, wind, gusts; a step recorded at the control
            rate, for its step response).
        plant: the vehicle that really flies, when a spread makes it differ from the
            nominal one (None: the nominal vehicle).
    """

    name: str
    reference: Reference
    world: World
    settings: SimSettings
    plant: VehicleParams | None = None


@dataclass(frozen=True, eq=False)
class TuneSet:
    """References and a mission grid.

    Attributes:
        name: the set's file or shipped name, for reports.
        references: (reference, its spec or file) pairs.
        seeds: seeds the references are flown with (their gusts): the missions'
            simulation seeds.
        winds: steady forces the references are flown in, N.
        gusts: gust levels the references are flown in, N.
        missions: the mission grid (None: references only).
    """

    name: str
    references: tuple[tuple[Reference, str], ...]
    seeds: tuple[int, ...]
    winds: tuple[tuple[float, float, float], ...]
    gusts: tuple[float, ...]
    missions: BatchSpec | None


def _shipped(name: str):
    return resources.files("quadnav.tune") / "sets" / f"{name}.toml"


def read_set(source: str | Path, vehicle: str) -> TuneSet:
    """The set in the TOML file ``source`` or the shipped set of that name
    (:data:`SHIPPED_SETS`); ``vehicle`` (a preset or file) is the missions' vehicle.
    QuadnavError (one line naming the file) for any mistake."""
    if str(source) in SHIPPED_SETS:
        with resources.as_file(_shipped(str(source))) as real:
            return _parse(read_toml(real), real.parent, str(source), vehicle)
    path = Path(source)
    return _parse(read_toml(path), path.parent, str(path), vehicle)


def _parse(table: dict[str, Any], folder: Path, name: str, vehicle: str) -> TuneSet:
    table = dict(table)
    specs = table.pop("references", [])
    if not isinstance(specs, list) or not all(isinstance(s, str) for s in specs):
        raise QuadnavError(f"{name}: references: expected a list of reference specs or "
                           f"files, got {specs!r}")
    for key in ("vehicle", "gains"):
        if key in table:
            raise QuadnavError(f"{name}: {key}: a tune set takes no {key} (the tuner's "
                               "--params and the gains tried set them)")
    if not specs and "maps" not in table:
        raise QuadnavError(f"{name}: expected references, maps or both")
    grid = {"maps": ["empty"], "speeds": [1.0], "seeds": [0]} | table | {"vehicle": vehicle}
    spec = spec_from_table(grid, folder, name)
    references = tuple((_reference(s, folder, name), s) for s in specs)
    return TuneSet(name, references, spec.flight_seeds, spec.winds, spec.gusts,
                   spec if "maps" in table else None)


def _reference(spec: str, folder: Path, name: str) -> Reference:
    """A built-in reference, or a file relative to the set's folder."""
    path = folder / spec
    try:
        return load_reference(path if path.is_file() else spec)
    except QuadnavError as error:
        raise QuadnavError(f"{name}: references: {error}") from None


def reference_items(tune_set: TuneSet) -> list[TuneItem]:
    """Every reference of the set flown with every seed, wind and gust level."""
    items = []
    for (reference, spec), seed, wind, gusts in product(
            tune_set.references, tune_set.seeds, tune_set.winds, tune_set.gusts):
        settings = SimSettings(wind=wind, gust_std=gusts, seed=seed)
        if isinstance(reference, StepReference) and reference.is_step:
            settings = settings.replace(record_rate=settings.control_rate)
        label = spec + _disturbance(wind, gusts) + f", seed {seed}"
        items.append(TuneItem(label, reference, track_world(reference), settings))
    return items


def _disturbance(wind: tuple[float, float, float], gusts: float) -> str:
    words = ([f"wind {list(wind)} N"] if any(wind) else []) + (
        [f"gusts {gusts:g} N"] if gusts else [])
    return f" ({', '.join(words)})" if words else ""


def mission_item(context: BatchContext, mission: MissionSpec, cache: StageCache) -> TuneItem:
    """``mission`` planned, and its trajectory made, with the context's gains (planning
    warnings silenced), each found in ``cache`` when made before. QuadnavError for a bad
    query or a mission that finds no path."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanningWarning)
        settings = mission_settings(context, mission)
        world = context.world_hashes[mission.map.map]
        problem = mission_problem(context, mission, settings.body, cache)
        key, planned = cache.plan(world, problem, settings)
        seed = f"seed {mission.seed}" + ("" if mission.sim_seed is None
                                         else f", sim seed {mission.sim_seed}")
        label = (f"{mission.map.map} {speed_text(mission.speed)} "
                 f"m/s{_disturbance(mission.wind, mission.gusts)}, {seed}")
        if not planned.plan.solved:
            raise QuadnavError(f"{label}: no path to fly ({planned.plan.message})")
        reference, settings, _ = cache.reference(key, planned, settings)
    return TuneItem(label, reference, problem.world, settings.sim, settings.plant)


def set_items(tune_set: TuneSet, vehicle: VehicleParams, gains: Gains,
              cache: StageCache | None = None) -> list[TuneItem]:
    """The items of ``tune_set``: its references, then its missions planned for
    ``vehicle`` flown with ``gains`` (the starting gains), their plans and trajectories
    kept in ``cache`` (None: one of this call's own)."""
    items = reference_items(tune_set)
    if tune_set.missions is not None:
        cache = cache or StageCache()
        context = load_context(tune_set.missions)
        context = BatchContext(context.fixed, vehicle, context.worlds,
                               dict.fromkeys(context.gains, gains))
        items += [mission_item(context, mission, cache)
                  for mission in tune_set.missions.missions()]
    return items
