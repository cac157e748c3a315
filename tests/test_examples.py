"""Every script in examples/ runs as documented and prints what it says: a planner, a
trajectory method, a reference and a controller of one's own, each in one file outside
the package, fly (the planner and the controller on a course map)."""

from __future__ import annotations

import runpy
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.fixture
def run_example(capsys, monkeypatch, registrations_forgotten):
    """``run(name, *args) -> stdout`` of ``python examples/name args``, in this process;
    the names an example registers are forgotten afterwards."""

    def run(name: str, *args: str) -> str:
        monkeypatch.setattr(sys, "argv", [str(EXAMPLES / name), *args])
        runpy.run_path(str(EXAMPLES / name), run_name="__main__")
        return capsys.readouterr().out

    return run


def test_every_example_is_tested():
    tested = {"plan.py", "fly.py", "custom_planner.py", "custom_trajectory.py",
              "custom_reference.py", "custom_controller.py", "batch_study.py",
              "plain_planner.py", "plain_trajectory.py", "plain_controller.py",
              "plain_wind.py"}
    assert {path.name for path in EXAMPLES.glob("*.py")} == tested


def test_plan_and_fly(run_example):
    assert run_example("plan.py").startswith("solved: ")
    assert run_example("fly.py").startswith("success True")


@pytest.mark.filterwarnings("ignore:start .* is inside the 0.3 m safety margin")
def test_a_planner_of_ones_own_flies_a_course_map(run_example, fetched_course_maps):
    out = run_example("custom_planner.py", "course:meam620/test_window")
    assert out.startswith("test_window by PRM: success True"), out


def test_a_plain_planner_function_flies_a_shipped_course_map(run_example):
    out = run_example("plain_planner.py")
    assert out.startswith("graph search at 0.25 m: success True"), out


def test_a_trajectory_method_of_ones_own_flies(run_example):
    out = run_example("custom_trajectory.py", "window")
    assert out.startswith("minimum jerk: success True"), out


def test_a_plain_trajectory_class_flies_a_shipped_course_map(run_example):
    out = run_example("plain_trajectory.py")
    assert out.startswith("stop and go at 1.5 m/s: success True"), out


def test_a_reference_of_ones_own_is_tracked(run_example):
    assert run_example("custom_reference.py").startswith("rose in open space: completed")
    out = run_example("custom_reference.py", "course:rotorpy/pillar", "3", "3", "1.5")
    assert out.startswith("rose in pillar round (3.0, 3.0, 1.5): completed"), out
    # a petal through the pillar (x -1 .. -0.75, y -0.125 .. 0.125)
    out = run_example("custom_reference.py", "course:rotorpy/pillar", "-0.4", "-0.85", "1.5")
    assert out.startswith("rose in pillar round (-0.4, -0.85, 1.5): collision"), out


def test_a_batch_study(run_example, tmp_path):
    lines = run_example("batch_study.py", str(tmp_path / "study")).splitlines()
    assert len(lines) == 4 and all(" 4 of 4, interval 51 to 100 %" in line for line in lines)


@pytest.mark.filterwarnings("ignore:start .* is inside the 0.3 m safety margin")
def test_a_controller_of_ones_own_flies_a_course_map_and_removes_the_winds_offset(
        run_example, fetched_course_maps):
    lines = run_example("custom_controller.py", "course:meam620/test_window")
    plain, integral = (float(line.split("final error ")[1].split(" cm")[0])
                       for line in lines.splitlines())
    assert all("success True" in line for line in lines.splitlines()), lines
    assert integral < 1.0 < plain, lines


#: Loads examples/custom_controller.py's controller in a fresh process, as a plug-in
#: (``file.py:Name``, as ``--controller`` does) or imported as a module of its own name,
#: compiles its step and prints how many times numba found it in its cache.
LOAD_CONTROLLER = """
import sys
from quadnav.plugins import load_target
from quadnav.vehicle.dynamics import vehicle_arrays
from quadnav.vehicle.params import load_params
folder, how = sys.argv[1:]
if how == "plug-in":
    factory = load_target(folder + "/custom_controller.py:se3_integral", "controller")
else:
    sys.path.insert(0, folder)
    from custom_controller import se3_integral as factory
vehicle = vehicle_arrays(load_params("tello"))
controller = factory(vehicle)
controller.compiled_step(vehicle)
print(sum(controller.step.stats.cache_hits.values()))
"""


def test_a_compiled_controller_of_ones_own_is_loaded_from_numbas_cache_when_run_again(
        tmp_path):
    """Its step, compiled once and cached beside the file, is loaded from numba's cache by
    the next run instead of compiled again (a second or so each run): its gains are of
    types numba finds again. And a file loaded as a plug-in and then imported by a
    script of one's own (another module name in numba's cache entry) still flies."""
    shutil.copy(EXAMPLES / "custom_controller.py", tmp_path)

    def cache_hits(how: str) -> int:
        done = subprocess.run([sys.executable, "-c", LOAD_CONTROLLER, str(tmp_path), how],
                              capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stderr
        return int(done.stdout)

    assert cache_hits("plug-in") == 0
    assert cache_hits("plug-in") == 1
    assert cache_hits("module") == 0  # the plug-in's entry dropped, compiled again


@pytest.mark.filterwarnings("ignore:start .* is inside the 0.3 m safety margin")
def test_a_plain_python_controller_flies_a_course_map(run_example, fetched_course_maps):
    out = run_example("plain_controller.py", "course:meam620/test_window")
    assert out.startswith("PD attitude in course:meam620/test_window: success True"), out
    assert float(out.split("RMS tracking error ")[1].split(" cm")[0]) < 5.0, out


def test_a_plain_python_wind_blows_a_flight_off_its_track_and_it_still_arrives(run_example):
    still, front = run_example("plain_wind.py").splitlines()
    assert still.startswith("still air in forest: success True"), still
    assert front.startswith("gust front in forest: success True"), front
    errors = [float(line.split("RMS tracking error ")[1].split(" cm")[0])
              for line in (still, front)]
    assert errors[1] > 3 * errors[0], (still, front)
