"""One mission configuration (quadnav.missionconfig): a mission file checked key by key, the
flags set on top of it, the run folder's mission.toml that flies again exactly, and one
builder that every command's mission goes through."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
from clitools import assert_user_error, run_here

from quadnav.batch.fly_one import fly_mission_spec, fly_row, load_context
from quadnav.batch.grid import spec_from_table
from quadnav.batch.stages import StageCache
from quadnav.cli.main import build_parser
from quadnav.cli.mission_args import mission_config
from quadnav.config import as_plain
from quadnav.control.gains import CASCADE_SETS, Gains, gain_set
from quadnav.control.registry import controller_gains
from quadnav.errors import QuadnavError
from quadnav.limits import MAX_SPEED, SPEED, speed_value
from quadnav.mission import MissionSettings
from quadnav.missionconfig import MISSION_FILE, MissionConfig, read_mission
from quadnav.tune.sets import mission_item
from quadnav.vehicle.params import load_params
from quadnav.world import World, load_world

SMALL = "window:size=4x6x3,walls=1"
#: The checkout's examples/, whose plain-Python plug-ins the tests fly.
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
#: Wall-time columns of metrics.json, which differ between two flights of one mission.
WALL_TIMES = {"planning_time_s", "trajectory_time_s", "sim_load_time_s", "sim_wall_time_s",
              "real_time_factor"}


def fly_args(*flags: str):
    """``quadnav fly`` 's parsed flags."""
    return build_parser(["fly", *flags]).parse_args(["fly", *flags])


def _metrics(folder) -> dict:
    metrics = json.loads((folder / "metrics.json").read_text())
    return {key: value for key, value in metrics.items() if key not in WALL_TIMES}


# ---------------------------------------------------------------------------- the file
def test_a_mission_file_reads_back_from_its_own_text(tmp_path):
    (tmp_path / "gains.toml").write_text("kx = [7.0, 7.0, 14.0]\n")
    (tmp_path / "sg.txt").write_text("start: (1, 1, 1)\ngoal: (3, 5, 2)\n")
    path = tmp_path / "m.toml"
    path.write_text(f"""
map = "{SMALL}"
seed = 4
trajectory = {{speed = "max", method = "quintic"}}
[query]
start_goal = "sg.txt"
margin = 0.25
[controller]
name = "se3"
gains = "gains.toml"
[disturbances]
wind = [0.01, 0, 0]
spread = {{mass = 0.1}}
""")
    config = read_mission(path)

    assert config.trajectory.speed == MAX_SPEED and config.trajectory.accel == 3.0
    assert config.query.start_goal == str(tmp_path / "sg.txt")  # against the file's folder
    assert config.controller.gains == str(tmp_path / "gains.toml")
    assert config.disturbances.spread.thrust == 0.0 and config.disturbances.wind[0] == 0.01
    (tmp_path / "again.toml").write_text(config.toml("a comment"))
    assert read_mission(tmp_path / "again.toml") == config
    settings = config.settings()
    assert settings.fastest and settings.gains.kx.tolist() == [7.0, 7.0, 14.0]
    assert settings.plant is not None and settings.plant.mass != settings.vehicle.mass
    world = config.world()
    problem = config.problem(world, settings.body)
    assert problem.start.tolist() == [1.0, 1.0, 1.0] and problem.margin == 0.25


@pytest.mark.parametrize(("text", "message"), [
    ("map = 'forest'\n\n[trajectory]\nsped = 3\n", "m.toml:4: trajectory.sped: unknown key; expected one of method, timing, speed, accel, reference, duration"),
    ("[trajectory]\nspeed = 0\n", 'm.toml:2: trajectory.speed: expected from 0.01 to 100 m/s or "max", got 0'),
    ("trajectory = {speed = 'fast'}\n", "m.toml:1: trajectory.speed: expected from 0.01 to 100 m/s or \"max\", got 'fast'"),
    ("seed = 1\nbogus = 2\n", "m.toml:2: bogus: unknown key; expected one of map, seed, vehicle, query, planner, trajectory, controller, simulation, disturbances"),
    ("[query]\nstart = [1, 2]\n", "m.toml:2: query.start: expected [x, y, z], each from -10,000 to 10,000 m, got [1, 2]"),
    ("[planner]\nname = 'rrt'\n", "m.toml:2: planner.name: unknown planner 'rrt'; expected one of rrtstar"),
    ("[planner]\niterations = 1.5\n", "m.toml:2: planner.iterations: expected a whole number from 0 to 5,000,000, got 1.5"),
    ("[controller]\nname = 'pid'\n", "m.toml:2: controller.name: unknown controller 'pid'; expected one of cascade, se3"),
    ("[disturbances]\nspread = {mas = 0.1}\n", "m.toml:2: disturbances.spread.mas: unknown key; expected one of mass, thrust, drag"),
    ("[disturbances]\nwind = [0, 0, 500]\n", "m.toml:2: disturbances.wind: expected [fx, fy, fz], each from -100 to 100 N, got [0, 0, 500]"),
    ("simulation = 3\n", "m.toml:1: simulation: expected a table [simulation], got 3"),
    ("vehicle = 'jet'\n", "m.toml:1: vehicle: jet: expected a vehicle preset (rbe595, tello), a TOML file or a rotorpy parameter dict"),
    ("[vehicle]\nmass = -1.0\n", "m.toml:1: vehicle: mass must be > 0, got -1.0"),
    ("map = 'nowhere.txt'\n", "m.toml:1: map: nowhere.txt: no such map file"),
    ("[query]\nstart_goal = 'none.txt'\n", "m.toml:2: query.start_goal: none.txt: cannot read"),
    ("[controller]\nname = 'se3'\n[controller.gains]\nkp = [1, 1, 1]\n", "m.toml:3: controller.gains: unknown key 'kp'; expected one of kx, kv, kr, kw"),
    ("[simulation]\ncontrol_rate = 300\n", "m.toml: the physics rate (1000 Hz) must be a whole multiple of the control rate (300 Hz)"),
    ("[trajectory\nspeed = 2\n", "m.toml: not valid TOML"),
])
def test_a_bad_mission_file_is_one_line_naming_the_file_line_and_key(tmp_path, text, message):
    (tmp_path / "m.toml").write_text(text)

    result = run_here("fly", "--mission", "m.toml", "-o", "out", cwd=tmp_path)

    assert_user_error(result, message)
    assert not (tmp_path / "out").exists()


def test_a_plug_in_file_beside_the_mission_file_is_found_from_any_folder(tmp_path):
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "ctl.py").write_text(
        "from quadnav.control.se3 import se3_controller\n\n\n"
        "def geometric(vehicle, gains=None):\n    return se3_controller()\n")
    (tmp_path / "mine" / "m.toml").write_text(
        f"map = '{SMALL}'\nplanner = {{improve = 500}}\n[controller]\nname = 'ctl.py:geometric'\n")
    (tmp_path / "elsewhere").mkdir()

    result = run_here("fly", "--mission", "../mine/m.toml", "--no-figures", "-o", "out",
                      cwd=tmp_path / "elsewhere")

    assert result.returncode == 0, result.stderr
    kept = read_mission(tmp_path / "elsewhere" / "out" / MISSION_FILE)
    assert kept.controller.name == f"{tmp_path / 'mine' / 'ctl.py'}:geometric"


def test_the_flags_given_set_their_keys_on_top_of_a_mission_file(tmp_path):
    path = tmp_path / "m.toml"
    path.write_text("map = 'forest'\nseed = 2\n[query]\nstart = [1, 1, 1]\ngoal = [19, 19, 3]\n"
                    "[controller]\nname = 'se3'\ngains = {kx = [7, 7, 14]}\n")
    base = read_mission(path)

    faster = base.with_changes({"trajectory.speed": 3.0}, {"trajectory.speed": "--speed"})
    assert faster.trajectory.speed == 3.0 and faster.seed == 2
    assert faster.controller.gains == {"kx": [7, 7, 14]}
    cascade = base.with_changes({"controller.name": "cascade"})
    assert cascade.controller.gains is None  # the se3 gains went with the se3 controller
    (tmp_path / "sg.txt").write_text("start: (2, 2, 1)\ngoal: (18, 18, 2)\n")
    moved = base.with_changes({"query.start_goal": str(tmp_path / "sg.txt")})
    assert moved.query.start is None and moved.ends(load_world("forest"))[0].tolist() == [
        2.0, 2.0, 1.0]
    with pytest.raises(QuadnavError, match=r"^--planner: unknown planner 'rrt'"):
        base.with_changes({"planner.name": "rrt"}, {"planner.name": "--planner"})


def test_one_speed_rule_and_one_margin_rule():
    assert [speed_value(v) for v in (2, 2.5, "max", " MAX ", 0, 101, "2", True)] == [
        2.0, 2.5, "max", "max", None, None, None, None]
    for bad in (0, "fast", SPEED.high * 2):
        with pytest.raises(QuadnavError, match="or \"max\""):
            MissionConfig.from_table({"trajectory": {"speed": bad}})
    own = World([0, 0, 0, 5, 5, 3], margin=0.3)
    bare = World([0, 0, 0, 5, 5, 3])
    assert (own.margin_for(), own.margin_for(0.1), bare.margin_for()) == (0.3, 0.1, 0.2)
    assert MissionConfig().margin(own) == 0.3
    assert MissionConfig.from_table({"query": {"margin": 0.05}}).margin(own) == 0.05


# ------------------------------------------------------------------- the run folder's
def test_a_run_folder_flies_again_exactly_from_its_mission_file(tmp_path):
    (tmp_path / "gains.toml").write_text("[position]\nkp = [2.0, 2.0, 2.5]\n")
    first = run_here("fly", SMALL, "--seed", "5", "--improve", "500", "--speed", "1",
                     "--gains", "gains.toml", "--params", "rbe595", "--no-figures",
                     "-o", "first", cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    kept = read_mission(tmp_path / "first" / MISSION_FILE)
    assert kept.trajectory.speed == 1.0 and kept.vehicle == "rbe595"
    assert kept.controller.gains["position"]["kp"] == [2.0, 2.0, 2.5]  # by its values
    assert kept.query.margin == 0.2 and kept.query.start == (1.0, 1.0, 1.0)
    (tmp_path / "gains.toml").unlink()  # the folder needs no other file

    again = run_here("refly", tmp_path / "first", "--no-figures", "-o", tmp_path / "again")
    flags = run_here("fly", "--mission", tmp_path / "first" / MISSION_FILE, "--no-figures",
                     "-o", tmp_path / "flags", "--seed", "5")

    assert again.returncode == 0 and flags.returncode == 0, again.stderr + flags.stderr
    assert _metrics(tmp_path / "again") == _metrics(tmp_path / "first")
    assert _metrics(tmp_path / "flags") == _metrics(tmp_path / "first")
    assert ((tmp_path / "again" / MISSION_FILE).read_text()
            == (tmp_path / "first" / MISSION_FILE).read_text())
    assert_user_error(run_here("refly", tmp_path, "-o", tmp_path / "x"),
                      f"{tmp_path}: no mission.toml: expected a run folder of quadnav fly")


#: A vehicle of the user's own as a rotorpy parameter dict, plain Python (no rotorpy).
MY_PARAMS = """\
import numpy as np

d = 0.1 / np.sqrt(2)
quad_params = {
    "mass": 0.25, "Ixx": 4e-4, "Iyy": 5e-4, "Izz": 8e-4, "num_rotors": 4,
    "rotor_pos": {"r1": d * np.array([1, -1, 0]), "r2": d * np.array([-1, 1, 0]),
                  "r3": d * np.array([1, 1, 0]), "r4": d * np.array([-1, -1, 0])},
    "rotor_directions": np.array([-1, -1, 1, 1]), "k_eta": 2e-7, "k_m": 4e-9, "tau_m": 0.03,
    "rotor_speed_max": 2500, "k_d": 2e-6, "k_z": 1e-6, "c_Dx": 0.01, "c_Dy": 0.01,
}
"""


def test_a_run_of_plain_python_plug_ins_flies_again_exactly(tmp_path):
    """A controller, a wind, a reference and a planner of your own and a rotorpy dict as the
    vehicle, given as flags from the folder that holds them: the run folder's mission.toml
    names the plug-ins by their absolute paths and the vehicle by its values, and flies the
    same flight again from anywhere, without the vehicle's file."""
    (tmp_path / "here").mkdir()
    (tmp_path / "here" / "my_params.py").write_text(MY_PARAMS)
    for name in ("plain_controller.py", "plain_wind.py", "plain_trajectory.py",
                 "plain_planner.py"):
        (tmp_path / "here" / name).write_text((EXAMPLES / name).read_text())
    first = run_here("fly", SMALL, "--improve", "500", "--params", "my_params.py:quad_params",
                     "--controller", "plain_controller.py:PDAttitude(kp=6.0)",
                     "--gains", "p2a-starter", "--wind", "plain_wind.py:GustFront(speed=2.0)",
                     "--reference", "plain_trajectory.py:StopAndGo(speed=1.0)",
                     "--duration", "12", "--planner", "plain_planner.py:graph_search",
                     "--control-rate", "250", "--no-figures", "-o", "first",
                     cwd=tmp_path / "here")
    assert first.returncode == 0, first.stderr

    kept = read_mission(tmp_path / "here" / "first" / MISSION_FILE)
    here = tmp_path / "here"
    assert kept.controller.name == f"{here / 'plain_controller.py'}:PDAttitude(kp=6.0)"
    assert kept.disturbances.wind_model == f"{here / 'plain_wind.py'}:GustFront(speed=2.0)"
    assert kept.trajectory.reference == f"{here / 'plain_trajectory.py'}:StopAndGo(speed=1.0)"
    assert (kept.trajectory.duration, kept.planner.name) == (
        12.0, f"{here / 'plain_planner.py'}:graph_search")
    assert kept.vehicle["mass"] == 0.25 and kept.vehicle["rotor_drag"] == [2e-6, 2e-6, 1e-6]
    # the inner loops' gains, the course table's, kept by their values
    assert kept.controller.gains["position"] == as_plain(controller_gains(
        "cascade", load_params("tello"), "p2a-starter").position)
    (tmp_path / "here" / "my_params.py").unlink()  # the vehicle is kept by its values

    again = run_here("refly", tmp_path / "here" / "first", "--no-figures", "-o", "again",
                     cwd=tmp_path)
    mission = run_here("fly", "--mission", tmp_path / "here" / "first" / MISSION_FILE,
                       "--no-figures", "-o", "flags", "--wind", "plain_wind.py:GustFront("
                       "speed=2.0)", cwd=tmp_path / "here")

    assert again.returncode == 0 and mission.returncode == 0, again.stderr + mission.stderr
    flown = _metrics(tmp_path / "here" / "first")
    for folder in (tmp_path / "again", tmp_path / "here" / "flags"):
        metrics = _metrics(folder)
        assert metrics.pop("planner") == kept.planner.name  # as kept: by its absolute path
        assert metrics == {key: value for key, value in flown.items() if key != "planner"}
    assert ((tmp_path / "again" / MISSION_FILE).read_text()
            == (tmp_path / "here" / "first" / MISSION_FILE).read_text())


def test_the_wind_flag_sets_the_whole_wind_over_a_mission_file(tmp_path):
    path = tmp_path / "m.toml"
    gust = f"{EXAMPLES / 'plain_wind.py'}:GustFront"
    path.write_text(f"[disturbances]\nwind = [0.01, 0, 0]\nwind_model = '{gust}(speed=2)'\n")
    base = read_mission(path)
    assert base.disturbances.wind == (0.01, 0.0, 0.0)  # both, beside each other, in a file
    model = mission_config(fly_args("--mission", str(path), "--wind", gust)).disturbances
    assert (model.wind, model.wind_model) == ((0.0, 0.0, 0.0), gust)
    force = mission_config(fly_args("--mission", str(path), "--wind", "0", "0.02", "0"))
    assert (force.disturbances.wind, force.disturbances.wind_model) == ((0.0, 0.02, 0.0), None)
    with pytest.raises(QuadnavError, match=r"^--wind: expected three forces"):
        mission_config(fly_args("--wind", "0", "0.02"))


def test_a_duration_needs_a_reference(tmp_path):
    with pytest.raises(QuadnavError, match=r"^the mission: trajectory.duration: applies only "
                                           "to a trajectory class of your own"):
        MissionConfig.from_table({"trajectory": {"duration": 5.0}})
    (tmp_path / "m.toml").write_text("[trajectory]\nspeed = 1.0\nduration = 5.0\n")
    assert_user_error(run_here("fly", "--mission", "m.toml", "-o", "out", cwd=tmp_path),
                      "m.toml:3: trajectory.duration: applies only to a trajectory class")


def test_a_batch_row_flies_again_from_its_refly_mission_file(tmp_path):
    spec = tmp_path / "spec.toml"
    spec.write_text(f'maps = ["{SMALL}"]\nseeds = [3]\nspeeds = [1.5]\nimprove = 500\n'
                    "gusts = [0.005]\nspreads = [0.1]\n")
    assert run_here("batch", spec, "--workers", "1", "--quiet", "-o", tmp_path / "b"
                    ).returncode == 0
    assert run_here("refly", tmp_path / "b", "1", "--no-figures", "-o", tmp_path / "row"
                    ).returncode == 0

    flown = run_here("fly", "--mission", tmp_path / "row" / MISSION_FILE, "--no-figures",
                     "-o", tmp_path / "fly")

    assert flown.returncode == 0, flown.stderr
    assert _metrics(tmp_path / "fly") == _metrics(tmp_path / "row")
    assert read_mission(tmp_path / "row" / MISSION_FILE).disturbances.spread.mass == 0.1


# ------------------------------------------------------------------------ one builder
MARK_TOLERANCE = 0.0987
MARK_SEED = 424242


def _marking(builder):
    """The one builder, adding a setting no command sets itself: what a key added to it
    does."""
    def settings(config, files=None):
        built = builder(config, files)
        return dataclasses.replace(
            built, planning=built.planning.replace(seed=MARK_SEED),
            sim=built.sim.replace(goal_tolerance=MARK_TOLERANCE))
    return settings


def test_a_setting_the_one_builder_adds_reaches_every_command(tmp_path, monkeypatch):
    monkeypatch.setattr(MissionConfig, "settings", _marking(MissionConfig.settings))
    improve = ["--improve", "500"]

    # fly, and refly of its run folder
    assert run_here("fly", SMALL, *improve, "--no-figures", "-o", tmp_path / "fly"
                    ).returncode == 0
    assert run_here("refly", tmp_path / "fly", "--no-figures", "-o", tmp_path / "refly"
                    ).returncode == 0
    for folder in ("fly", "refly"):
        metrics = json.loads((tmp_path / folder / "metrics.json").read_text())
        assert (metrics["seed"], metrics["goal_tolerance_m"]) == (MARK_SEED, MARK_TOLERANCE)
    # each mission of a batch (what a worker runs for it), and tune's missions
    spec = spec_from_table({"maps": [SMALL], "seeds": [1], "speeds": [1.0], "improve": 500},
                           tmp_path)
    context = load_context(spec)
    (mission,) = spec.missions()
    assert fly_row(context, mission)["goal_tolerance_m"] == MARK_TOLERANCE
    assert mission_item(context, mission, StageCache()).settings.goal_tolerance == MARK_TOLERANCE
    # tello fly plans with the builder's planner settings
    (tmp_path / "room.txt").write_text("boundary 0 0 0 6 2 1.5\n")
    tello = run_here("tello", "fly", tmp_path / "room.txt", "--start", "1", "1", "0",
                     "--goal", "5", "1", "0", *improve, "--dry-run", "--no-figures",
                     "--quiet", "-o", tmp_path / "tello")
    assert tello.returncode == 0, tello.stderr
    assert json.loads((tmp_path / "tello" / "metrics.json").read_text())["seed"] == MARK_SEED
    # and the library's missions
    flown = MissionConfig.from_table({"map": SMALL, "planner": {"improve": 500}}).fly()
    assert flown.settings.sim.goal_tolerance == MARK_TOLERANCE


def test_fly_flies_the_mission_a_batch_builds_from_the_same_settings(tmp_path):
    spec = spec_from_table({"maps": [SMALL], "seeds": [7], "speeds": [1.0], "accel": 2.0,
                            "gusts": [0.005], "winds": [[0.005, 0, 0]], "spreads": [0.1],
                            "vehicle": "rbe595", "gains": ["p2a-starter"], "improve": 500,
                            "time_cap": 30.0}, tmp_path)
    (mission,) = spec.missions()
    row = fly_mission_spec(load_context(spec), mission)

    flags = run_here("fly", SMALL, "--seed", "7", "--speed", "1", "--accel", "2",
                     "--gusts", "0.005", "--wind", "0.005", "0", "0", "--params", "rbe595",
                     "--gains", "p2a-starter", "--improve", "500", "--time", "30",
                     "--no-figures", "-o", tmp_path / "fly")

    assert flags.returncode in (0, 1), flags.stderr  # flown either way: the settings count
    parameters = json.loads((tmp_path / "fly" / "parameters.json").read_text())
    batch = json.loads(json.dumps(row.parameters()))
    assert {key: value for key, value in batch.items() if key != "plant"} == parameters
    assert "plant" in batch  # the batch's spread, which fly has no flag for
    assert parameters["gains"] == as_plain(controller_gains("cascade", load_params("rbe595"),
                                                           "p2a-starter"))


def test_the_library_defaults_are_the_builders():
    built, library = MissionConfig().settings(), MissionSettings()
    for key in ("planner", "planning", "refine", "trajectory", "fastest", "vehicle", "gains",
                "controller", "sim", "plant", "reference", "reference_duration"):
        assert as_plain(getattr(built, key)) == as_plain(getattr(library, key)), key
    rbe595 = MissionSettings(vehicle=load_params("rbe595"))
    assert as_plain(MissionConfig(vehicle="rbe595").settings().flown_gains) == as_plain(
        rbe595.flown_gains)
    assert as_plain(rbe595.flown_gains) == as_plain(gain_set(Gains(), CASCADE_SETS, "rbe595"))
