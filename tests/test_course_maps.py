"""Course maps for users: rotorpy's worlds shipped with the package, the other public course
maps fetched with ``quadnav maps fetch`` (from a loopback server here) into the cache, and
``course:NAME`` wherever a map or a start/goal file is accepted."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from urllib.parse import urlsplit

import pytest
from clitools import assert_user_error, run_here
from coursemaps import dead_url, serving, zipped
from publicmaps import START_GOAL_FILES, START_GOAL_POINTS, far_apart_free_points

from quadnav.batch.grid import spec_from_table
from quadnav.world import load_world, read_start_goal
from quadnav.world.courses import (
    CACHE_ENV,
    URL_ENV,
    CourseMap,
    cache_dir,
    cached_path,
    catalogue,
    sha256,
)

SHIPPED = [entry for entry in catalogue().values() if entry.shipped is not None]
FETCHED = [entry for entry in catalogue().values() if entry.shipped is None]
SHIPPED_FOLDER = Path(__file__).resolve().parents[1] / "src/quadnav/world/coursemaps"


@pytest.fixture
def cache(tmp_path, monkeypatch) -> Path:
    """An empty cache of course maps for this test, and downloads from a dead port unless
    the test points them elsewhere."""
    folder = tmp_path / "cache"
    monkeypatch.setenv(CACHE_ENV, str(folder))
    monkeypatch.setenv(URL_ENV, dead_url())
    return folder


def _files(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*") if p.is_file()) if folder.exists() else []


def _list_rows() -> dict[str, str]:
    """``quadnav maps list``: the status of each course map, by name."""
    result = run_here("maps", "list")
    assert result.returncode == 0, result.stderr
    rows = result.stdout.splitlines()[1:len(catalogue()) + 1]
    return {row.split()[0]: next(s for s in ("not fetched", "fetched", "shipped") if
                                 f"  {s}  " in row) for row in rows}


def test_the_shipped_worlds_are_rotorpys_files_byte_for_byte_with_its_licence():
    assert {e.name for e in SHIPPED} == {"rotorpy/pillar", "rotorpy/double_pillar",
                                        "meam620/grid_forest"}
    for entry in SHIPPED:
        data = (SHIPPED_FOLDER / entry.shipped).read_bytes()
        assert (sha256(data), len(data)) == (entry.sha256, entry.size), entry.name
        assert entry.repo == "spencerfolk/rotorpy" and entry.path.startswith("rotorpy/worlds/")
        assert (SHIPPED_FOLDER / entry.shipped).parent == SHIPPED_FOLDER / "rotorpy"
    licence = (SHIPPED_FOLDER / "rotorpy" / "LICENSE.md").read_text()
    assert licence.startswith("Copyright 2023 RotorPy Authors\n")
    assert "Permission is hereby granted, free of charge" in licence
    assert all(e.commit in (SHIPPED_FOLDER / "rotorpy" / "README.md").read_text()
               for e in SHIPPED)


def test_the_shipped_worlds_fly_offline_with_no_cache_and_no_network(cache):
    """Downloads go to a dead port here: a shipped world needs neither it nor the cache."""
    for entry in SHIPPED:
        world = load_world(f"course:{entry.name}")
        assert world.name == f"course:{entry.name}" and len(world) > 0
    result = run_here("maps", "info", "course:rotorpy/double_pillar")
    assert result.returncode == 0, result.stderr
    assert "bounds:      x -3.5 .. 3.5, y -5 .. 5, z -0.5 .. 3 m" in result.stdout
    assert "blocks:      2" in result.stdout
    result = run_here("fly", "course:rotorpy/double_pillar", "--start", "0", "-4", "1",
                      "--goal", "0", "4", "1", "--improve", "1000", "--no-figures", "--quiet",
                      "-o", cache.parent / "out")
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("course:rotorpy/double_pillar: success")
    assert _files(cache) == []


def test_loading_a_course_map_does_not_import_pooch():
    """pooch (and requests) load only to fetch."""
    code = ("import sys; from quadnav.world import load_world; "
            "load_world('course:rotorpy/pillar'); "
            "import quadnav.cli.map_commands; print('pooch' in sys.modules)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            timeout=60, check=True)
    assert result.stdout.strip() == "False"


def test_the_catalogue_pins_every_file_of_the_corpus(shared_maps):
    sources = json.loads((shared_maps / "SOURCES.json").read_text())
    assert sorted(e.file_name for e in catalogue().values()) == sorted(
        s["file"] for s in sources)
    for source in sources:
        entry = catalogue()[source["file"].rsplit(".", 1)[0]]
        pinned = {key: getattr(entry, key) for key in source if key != "file"}
        assert pinned == {key: value for key, value in source.items() if key != "file"}
        assert sha256((shared_maps / source["file"]).read_bytes()) == entry.sha256


def test_fetch_lists_and_flies_each_fetched_map(course_server, cache, monkeypatch, tmp_path,
                                                 shared_maps):
    monkeypatch.setenv(URL_ENV, course_server)
    before = _list_rows()
    assert before == {e.name: "shipped" if e.shipped else "not fetched"
                      for e in catalogue().values()}

    result = run_here("maps", "fetch")
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert "fetched rbe595/map1 (441 bytes, SHA-256 checked)" in result.stdout
    assert "fetched rbe595/p2b_map1 (204 bytes from TrainSetP2b.zip, SHA-256 checked)" in (
        result.stdout)
    assert result.stdout.splitlines()[-1] == f"cache: {cache}"
    assert _files(cache) == sorted(cache / e.file_name for e in FETCHED)
    for entry in FETCHED:
        assert cached_path(entry).read_bytes() == (shared_maps / entry.file_name).read_bytes()
    assert _list_rows() == {e.name: "shipped" if e.shipped else "fetched"
                            for e in catalogue().values()}
    again = run_here("maps", "fetch", "course:rbe595/map1", "rotorpy/pillar")
    assert again.stdout.splitlines()[:2] == ["rbe595/map1: already in the cache",
                                             "rotorpy/pillar: shipped with quadnav, nothing to "
                                             "fetch"]

    for entry in FETCHED:
        if entry.kind != "map":
            continue
        name = f"course:{entry.name}"
        result = run_here("fly", name, *_query(entry.file_name, name), "--improve", "1000",
                          "--no-figures", "--quiet", "-o", tmp_path / entry.name)
        if entry.name == "meam620/test_impossible":
            assert_user_error(result, name, "no path exists")
        else:
            assert result.returncode == 0, (name, result.stderr)
            assert result.stdout.startswith(f"{name}: success"), result.stdout


def _query(file_name: str, name: str) -> list[str]:
    """Start and goal flags of a fetched course map: the course's, else the map's own,
    else two far-apart free points."""
    if file_name in START_GOAL_FILES:
        return ["--start-goal", "course:" + START_GOAL_FILES[file_name].rsplit(".", 1)[0]]
    world = load_world(name)
    if file_name in START_GOAL_POINTS:
        start, goal = START_GOAL_POINTS[file_name]
    elif world.start is not None:
        return []
    else:
        start, goal = far_apart_free_points(world.inflate(0.2))
    return ["--start", *map(str, start), "--goal", *map(str, goal)]


def test_course_start_goal_files_are_read_wherever_a_start_goal_file_is(
        course_server, cache, monkeypatch, shared_maps):
    monkeypatch.setenv(URL_ENV, course_server)
    assert run_here("maps", "fetch", "rbe595/p2b_map1",
                    "rbe595/p2b_startandgoal_map1").returncode == 0
    start, goal = read_start_goal("course:rbe595/p2b_startandgoal_map1")
    assert start.tolist() == [0, 0, 0] and goal.tolist() == [-0.59, 6.81, 0]
    result = run_here("map", "check", "course:rbe595/p2b_map1", "--start-goal",
                      "course:rbe595/p2b_startandgoal_map1", "--margin", "0.1")
    assert result.returncode == 0, result.stderr
    assert "start (0, 0, 0):" in result.stdout and "goal (-0.59, 6.81, 0):" in result.stdout
    spec = spec_from_table({"maps": [{"map": "course:rbe595/p2b_map1",
                                      "start_goal": "course:rbe595/p2b_startandgoal_map1"}],
                            "seeds": 1, "speeds": [1.0]}, shared_maps)
    assert spec.maps[0].map == "course:rbe595/p2b_map1"
    assert (spec.maps[0].start, spec.maps[0].goal) == ((0, 0, 0), (-0.59, 6.81, 0))


def test_an_unfetched_map_names_the_fetch_command(cache):
    message = ("course:rbe595/map1: not fetched yet: run quadnav maps fetch rbe595/map1 first "
               "(it downloads the file from ShreyasKhobragade/RBE595-Tree-Planning-P2a on "
               "GitHub)")
    assert_user_error(run_here("map", "info", "course:rbe595/map1"), message)
    assert_user_error(run_here("fly", "--start-goal", "course:rbe595/p2b_startandgoal_map1"),
                      "course:rbe595/p2b_startandgoal_map1: not fetched yet: run quadnav maps "
                      "fetch rbe595/p2b_startandgoal_map1 first")
    assert_user_error(run_here("batch", "forest", "course:rbe595/map1", "-o", cache.parent),
                      "the command line: map: " + message)
    assert _files(cache) == []


def test_an_unknown_name_or_the_wrong_kind_is_one_line(cache):
    known = ", ".join(catalogue())
    assert_user_error(run_here("fly", "course:rbe595/map9"),
                      f"course:rbe595/map9: no such course map; known: {known} "
                      "(quadnav maps list)")
    assert_user_error(run_here("maps", "fetch", "rbe595/map9"), "rbe595/map9: no such course")
    assert_user_error(run_here("map", "info", "course:rbe595/p2b_startandgoal_map1"),
                      "a start/goal file, not a map: pass it with --start-goal")
    assert_user_error(run_here("fly", "--start-goal", "course:rotorpy/pillar"),
                      "course:rotorpy/pillar: a map, not a start/goal file: pass it as the map")


def test_a_wrong_hash_is_one_line_and_keeps_nothing(cache, monkeypatch):
    """A file, and a zip member, whose bytes are not the pinned ones."""
    plain, member = catalogue()["rbe595/map1"], catalogue()["rbe595/p2b_map1"]
    served = {plain: b"boundary 0 0 0 1 1 1\n", member: b"boundary 0 0 0 2 2 2\n"}
    with serving(_files_at_their_urls(served)) as url:
        monkeypatch.setenv(URL_ENV, url)
        for entry, where in ((plain, plain.url()),
                             (member, f"{member.url()} (TrainSetP2b/maps/map1.txt)")):
            result = run_here("maps", "fetch", entry.name)
            assert result.returncode == 1, result
            assert result.stderr.splitlines() == [
                f"quadnav: fetch failed: {entry.name}: the file from {where} does not have the "
                f"pinned SHA-256 {entry.sha256[:12]}...; nothing was kept (the origin or the "
                "download was changed)"]
            assert _files(cache) == []


def _files_at_their_urls(contents: dict[CourseMap, bytes]) -> dict[str, bytes]:
    """URL path -> bytes serving each entry's ``contents`` where it is fetched from (in a zip
    archive, for a member)."""
    return {urlsplit(entry.url("http://loopback")).path:
            data if entry.member is None else zipped({entry.member: data})
            for entry, data in contents.items()}


def test_a_dead_server_is_one_line_and_keeps_nothing(cache):
    for name in ("rbe595/map1", "rbe595/p2b_map1"):
        result = run_here("maps", "fetch", name)
        assert result.returncode == 1, result
        entry = catalogue()[name]
        assert result.stderr.splitlines() == [
            f"quadnav: fetch failed: {name}: cannot download {entry.url()}: Connection refused"]
        assert _files(cache) == []


def test_a_changed_file_in_the_cache_is_refused_and_fetched_again(cache):
    entry = catalogue()["rbe595/map4"]
    cached_path(entry).parent.mkdir(parents=True)
    cached_path(entry).write_text("boundary 0 0 0 1 1 1\n")
    assert_user_error(run_here("map", "info", "course:rbe595/map4"),
                      f"course:rbe595/map4: the cached file {cached_path(entry)} does not match "
                      "its pinned SHA-256: run quadnav maps fetch rbe595/map4 to fetch it again")
    assert _list_rows()["rbe595/map4"] == "not fetched"


def test_the_cache_is_poochs_user_cache_unless_the_variable_moves_it(monkeypatch, tmp_path):
    import pooch

    monkeypatch.delenv(CACHE_ENV, raising=False)
    assert cache_dir() == pooch.os_cache("quadnav")
    monkeypatch.setenv(CACHE_ENV, str(tmp_path))
    assert cache_dir() == tmp_path


def test_a_batch_summary_labels_course_maps_by_name_beside_files():
    """Course names are not files: the labels keep them whole (mixed with absolute paths
    they made the shared-folder computation fail)."""
    from quadnav.batch.summary_page import short_maps

    assert short_maps(["/data/maps/a.txt", "/data/maps/b.txt", "course:rbe595/map1",
                       "forest"]) == {"/data/maps/a.txt": "a.txt", "/data/maps/b.txt": "b.txt",
                                      "course:rbe595/map1": "course:rbe595/map1",
                                      "forest": "forest"}
