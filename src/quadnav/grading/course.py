"""What a course grades: :class:`Course`, read from the TA's course file (``grade.toml``,
:func:`read_course`) or built from the command line, and each of its missions
(:meth:`Course.missions`) as a :class:`~quadnav.missionconfig.MissionConfig`, flown once
with the submission's parts and once with quadnav's own (the baseline).

A course file is TOML (see docs/grading.md)::

    seeds = 2                       # seeds 0 and 1 on every map; or a list [0, 4]
    strict = false                  # true: a flight that keeps less margin than asked fails
    baseline = true                 # fly quadnav's own parts on the same missions too
    mission_time_limit = 300        # s a mission may run before it is stopped; 0: no limit

    [parts]                         # what each submission provides, in its own folder
    controller = "se3_control.py:SE3Control"
    planner = "graph_search.py:graph_search(resolution=0.25)"
    reference = "my_traj.py:MyTraj"

    [[maps]]                        # each map with its query (a mission file's [query] keys)
    map = "course:rotorpy/double_pillar"
    start = [-1.1, -3, 1]
    goal = [-1.1, 3, 1.5]

    [mission]                       # the rest of every mission: a mission file's keys
    planner = {improve = 2000}
    trajectory = {speed = 1.5}

Every key is checked (pydantic, as a mission file's: :mod:`quadnav.missionconfig`); a
mistake is one :class:`~quadnav.errors.QuadnavError` naming the file, the line and the key.
Relative paths in the file (maps, start/goal files, a vehicle file) are resolved against
its folder; the parts' files against the submission's folder (:func:`submission_spec`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

from pydantic import BeforeValidator, Field, ValidationError, field_validator

from quadnav.config import read_toml
from quadnav.errors import QuadnavError
from quadnav.limits import SEED, Range
from quadnav.missionconfig import MissionConfig, Query
from quadnav.missionconfig.checks import FileOrName, fail, flag, number, text
from quadnav.missionconfig.sections import Section
from quadnav.missionconfig.source import Source
from quadnav.plugins import parse_spec

#: The parts a submission may provide, each a key of :class:`Parts`, and the key of a
#: mission file it sets.
PART_KEYS = {"controller": "controller.name", "planner": "planner.name",
             "reference": "trajectory.reference"}
#: The keys of a mission that a course sets for each mission itself.
MISSION_OWN_KEYS = ("map", "seed", "query")
#: How many seeds a course may fly on each map.
SEED_COUNT = Range(1, 1000, whole=True)
#: Seeds of a course that does not say.
DEFAULT_SEEDS = 2
#: The wall-clock seconds a mission may run (0: no limit), and the limit of a course that
#: does not say: far longer than a mission takes (seconds), short enough that an endless
#: loop in a submission costs a grade minutes, not hours.
MISSION_TIME_LIMIT, DEFAULT_MISSION_TIME_LIMIT = Range(0, 86400, "s"), 300.0


def _spec(kind: str):
    """A check for :func:`~quadnav.missionconfig.checks.text`: a plug-in spec's syntax."""
    def check(value: str) -> None:
        parse_spec(value, kind)
    return check


class Parts(Section):
    """``[parts]``: what a submission provides, each ``file.py:Name`` in its folder (or a
    ``module:Name`` on Python's path), with literal keyword arguments; None: quadnav's own.

    Attributes:
        controller: a controller class in rotorpy's shape.
        planner: a planner function ``(world, start, goal, margin) -> path (N, 3)``.
        reference: a trajectory class in rotorpy's shape, flown instead of quadnav's
            trajectory.
    """

    controller: Annotated[str | None, text(_spec("controller"), optional=True)] = None
    planner: Annotated[str | None, text(_spec("planner"), optional=True)] = None
    reference: Annotated[str | None, text(_spec("reference"), optional=True)] = None

    def given(self) -> dict[str, str]:
        """The parts given, by key of :data:`PART_KEYS`."""
        return {key: value for key in PART_KEYS if (value := getattr(self, key)) is not None}


class CourseMap(Query):
    """One ``[[maps]]`` entry: a map and its query (the keys of a mission file's
    ``[query]``: ``start``, ``goal``, ``start_goal``, ``margin``), or just the map's name
    (``maps = ["forest:seed=3"]``) when it has its own start and goal."""

    map: FileOrName


def _map_entry(value: Any) -> Any:
    return {"map": value} if isinstance(value, str) else value


def _seeds(value: Any) -> Any:
    """A count N (seeds 0 to N - 1) or a non-empty list of distinct seeds."""
    if isinstance(value, list):
        if not value or len(set(map(repr, value))) != len(value):
            raise fail(f"expected a non-empty list of distinct seeds, got {value!r}")
        return [number(SEED).func(seed) for seed in value]
    return list(range(number(SEED_COUNT).func(value)))


class Course(Section):
    """A course's grading (see the module docstring).

    Attributes:
        maps: the maps, each with its query.
        seeds: the seeds flown on every map.
        strict: a flight that kept less margin than asked off the legs fails too.
        baseline: fly quadnav's own parts on the same missions, to compare.
        mission_time_limit: wall-clock seconds a mission may run (its flight, figures and
            report) before it is stopped and fails; 0: no limit.
        parts: what each submission provides.
        mission: every other setting of the missions (a mission file's keys but ``map``,
            ``seed`` and ``query``).
    """

    maps: list[Annotated[CourseMap, BeforeValidator(_map_entry)]]
    seeds: Annotated[list[int], BeforeValidator(_seeds)] = Field(
        default_factory=lambda: list(range(DEFAULT_SEEDS)))
    strict: Annotated[bool, BeforeValidator(flag)] = False
    baseline: Annotated[bool, BeforeValidator(flag)] = True
    mission_time_limit: Annotated[float, number(MISSION_TIME_LIMIT)] = \
        DEFAULT_MISSION_TIME_LIMIT
    parts: Parts = Parts()
    mission: MissionConfig = MissionConfig()

    @field_validator("maps")
    @classmethod
    def _some_maps(cls, maps: list[CourseMap]) -> list[CourseMap]:
        if not maps:
            raise fail("expected at least one map")
        return maps

    @field_validator("mission")
    @classmethod
    def _no_own_keys(cls, mission: MissionConfig) -> MissionConfig:
        own = [key for key in MISSION_OWN_KEYS if key in mission.model_fields_set]
        if own:
            raise fail(f"{', '.join(own)} is set for each mission by the course's maps and "
                       "seeds; give maps = [...] (with start, goal, margin) and seeds instead")
        return mission

    def missions(self) -> list[GradedMission]:
        """Every mission, map by map, seed by seed."""
        labels = map_labels([entry.map for entry in self.maps])
        return [GradedMission(number, labels[number], entry, seed)
                for number, entry in enumerate(self.maps) for seed in self.seeds]


@dataclass(frozen=True)
class GradedMission:
    """One mission of a course.

    Attributes:
        number: its map's place in the course's list (0-based).
        label: its map's short name, unique in the course (a file's stem, a course map's
            name), for folders and tables.
        entry: the map and its query.
        seed: the seed.
    """

    number: int
    label: str
    entry: CourseMap
    seed: int

    @property
    def key(self) -> str:
        """``LABEL/seed-N``: its folder under a grade's ``missions/PART``."""
        return f"{self.label}/seed-{self.seed}"

    def config(self, course: Course) -> MissionConfig:
        """The mission with quadnav's own parts (the course's ``[mission]``, its map,
        query and seed)."""
        query = self.entry.model_dump(exclude={"map"}, exclude_none=True)
        table = course.mission.table() | {"map": self.entry.map, "seed": self.seed,
                                           "query": query}
        return MissionConfig.from_table(table, source="the course")


def map_labels(maps: list[str]) -> list[str]:
    """A short, unique, file-name-safe label of each map: the name of a course map
    (``rotorpy-double_pillar``), the stem of a file, a built-in world's spec; numbered
    (``-2``) where two would be alike."""
    labels = []
    for name in maps:
        stem = name.removeprefix("course:") if name.startswith("course:") else (
            Path(name).stem if Path(name).suffix else name)
        safe = "".join(c if c.isalnum() or c in "-_.=" else "-" for c in stem).strip("-.")
        label, count = safe or "map", 1
        while label in labels:
            count += 1
            label = f"{safe}-{count}"
        labels.append(label)
    return labels


def submission_spec(text: str, folder: Path) -> str:
    """The part ``text`` of a submission in ``folder``: ``file.py:Name(...)`` with the file
    taken in ``folder`` (as an absolute path, whether it is there or not: a missing file is
    the submission's failure); a module or an absolute path as it is."""
    where, colon, rest = text.strip().partition(":")
    if not (colon and where.endswith(".py")) or Path(where).is_absolute():
        return text
    return f"{(folder / where).resolve()}:{rest}"


def read_course(path: str | Path | None, changes: Mapping[str, Any] | None = None,
                names: Mapping[str, str] | None = None) -> Course:
    """The course in the TOML file ``path`` (None: an empty one) with the top-level keys
    ``changes`` set on top (the command line's; ``names`` says how messages name each,
    e.g. ``--maps``). QuadnavError naming the file, the line and the key."""
    if path is None:
        table: dict[str, Any] = {}
        source = Source("the command line", None, dict(names or {}))
        folder = Path.cwd()
    else:
        path = Path(path)
        table = read_toml(path)
        source = Source(str(path), path.read_text(encoding="utf-8"), dict(names or {}))
        folder = path.parent
    for dotted, value in (changes or {}).items():
        *parents, key = dotted.split(".")
        place = table
        for parent in parents:
            place = place.setdefault(parent, {})
        place[key] = value
    if "maps" not in table:
        raise QuadnavError(f"{source.name}: no maps to grade on; give maps = [...] in a "
                           "course file (--course FILE) or --maps MAP ...")
    try:
        return Course.model_validate(table, context={"folder": folder})
    except ValidationError as error:
        raise source.refusal(error.errors()[0], Course) from None
