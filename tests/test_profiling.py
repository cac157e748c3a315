"""Where a mission's CPU goes, stage by stage (quadnav.profiling, bench/batch.py --stages):
a stage counts its own CPU and runs only while a profile is open, a batch mission names
every stage, and the work a map needs once runs once per map however many missions fly it.
No assertion rests on how long anything took."""

from __future__ import annotations

import time

import pytest

from quadnav.batch.fly_one import flown_row, load_context
from quadnav.batch.grid import read_spec
from quadnav.batch.stages import StageCache
from quadnav.batch.table import same_row
from quadnav.profiling import profiled, stage, staged

MAPS = ("window:size=4x6x3,walls=1", "forest:size=10x10x4,seed=1")
SPEC = f"""\
seeds = 3
speeds = [2.0]
improve = 500
maps = {list(MAPS)}
""".replace("'", '"')
#: Every stage a batch mission runs (the first on its map).
STAGES = {"query", "proof", "search", "first path", "improvement", "shortcut", "smoothing",
          "trajectory", "fastest timing", "simulation", "metrics", "row"}
ONCE_PER_MAP = {"inflated world", "block grid", "proof labels"}
LOADING = "loading the maps"


def _busy(seconds: float) -> None:
    """Spend about ``seconds`` of CPU."""
    end = time.process_time() + seconds
    while time.process_time() < end:
        pass


@staged("inner")
def _inner() -> None:
    _busy(0.01)


def test_a_stage_counts_its_own_cpu_and_runs_only_while_a_profile_is_open():
    _inner()  # no profile open: nothing recorded anywhere
    with profiled() as profile:
        began = time.process_time()
        with stage("outer"):
            _busy(0.01)
            _inner()
            _inner()
        spent = time.process_time() - began
        with profiled() as nested:
            _inner()
    _inner()

    assert dict(profile.runs) == {"outer": 1, "inner": 2}
    assert dict(nested.runs) == {"inner": 1}
    assert min(profile.seconds.values()) > 0
    # the outer stage's own seconds leave out the inner runs': the two add up to the time
    # spent inside it, not more
    assert sum(profile.seconds.values()) <= spent + 1e-9


@pytest.fixture(scope="module")
def flown(tmp_path_factory) -> tuple[list[str], list[dict], list[dict], list[dict]]:
    """The spec's missions flown one after the other with one stage cache each time, as a
    worker flies them (maps loaded afresh), profiled and not: each mission's map, its rows
    profiled, the stage runs of the maps' loading (a built-in world inflates itself to
    check that its start and goal are joined) and then of each mission, and the rows
    unprofiled."""
    spec_path = tmp_path_factory.mktemp("spec") / "spec.toml"
    spec_path.write_text(SPEC)
    spec = read_spec(spec_path)
    with profiled() as loading:
        context, cache = load_context(spec), StageCache()
    rows, runs = [], [dict(loading.runs)]
    for mission in spec.missions():
        with profiled() as stages:
            rows.append(flown_row(context, mission, cache))
        runs.append(dict(stages.runs))
    context, cache = load_context(spec), StageCache()
    plain = [flown_row(context, mission, cache) for mission in spec.missions()]
    return [LOADING, *(mission.map.map for mission in spec.missions())], rows, runs, plain


def test_a_batch_mission_names_every_stage_and_profiling_changes_no_row(flown):
    maps, rows, runs, plain = flown

    assert len(rows) == 3 * len(MAPS) and all(row["success"] for row in rows)
    assert runs[0] == {"inflated world": len(MAPS)}
    for k, (name, stages) in enumerate(zip(maps, runs, strict=True)):
        if name == LOADING:
            continue
        first = maps.index(name) == k
        # the query (given ends: the map's own) is checked once per map; each mission plans
        expected = STAGES | ONCE_PER_MAP - {"inflated world"} if first else STAGES - {
            "query", "proof"}
        assert set(stages) == expected
        assert stages["row"] == stages["simulation"] == stages["search"] == 1
    assert all(same_row(a, b) for a, b in zip(rows, plain, strict=True))


def test_work_a_map_needs_once_runs_in_the_first_mission_on_the_map_alone(flown):
    maps, _, runs, _ = flown

    loading = runs[0]
    for name in MAPS:
        first, *others = (stages for map_name, stages in zip(maps, runs, strict=True)
                          if map_name == name)
        assert all(first.get(stage, 0) + loading.get(stage, 0) >= 1 for stage in ONCE_PER_MAP)
        assert len(others) == 2 and not any(stage in ONCE_PER_MAP for stages in others
                                            for stage in stages)
