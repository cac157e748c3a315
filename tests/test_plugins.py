"""Plug-in points by name: planners and trajectory methods registered in a process or
declared by an installed package's entry points, and the mistakes a user can make."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from quadnav.errors import QuadnavError
from quadnav.planning import make_problem, plan, planner_names, register_planner
from quadnav.plugins import Lazy, OptionalWheel, PluginError, Registry
from quadnav.trajectory.generate import METHODS, TrajectorySettings, make_trajectory
from quadnav.trajectory.polynomials.minsnap import minimum_derivative
from quadnav.trajectory.references.builtin import REFERENCES, load_reference
from quadnav.vehicle import PRESETS, load_params, preset_names
from quadnav.world import load_world
from quadnav.world.builtin import WORLDS, build_world, empty


def test_a_registered_planner_is_planned_with_by_name(registrations_forgotten):
    calls = []

    def straight(problem, settings, progress=None):
        calls.append(settings.seed)
        return plan(problem, settings, "rrtstar")

    register_planner("mine", straight)
    world = load_world("forest:size=10x10x4")
    problem = make_problem(world, world.start, world.goal, 0.2)
    result = plan(problem, planner="mine")
    assert calls == [0] and result.solved
    assert "mine" in planner_names() and planner_names()[0] == "rrtstar"


@pytest.mark.parametrize(("name", "plugin", "message"), [
    ("", print, "planner name '': expected a word without spaces or colons"),
    ("my planner", print, "planner name 'my planner': expected a word without spaces"),
    ("ompl:mine", print, "planner name 'ompl:mine': expected a word without spaces"),
    ("rrtstar", print, "planner 'rrtstar' is already registered"),
    ("mine", 3, "planner 'mine': expected a function, got 3"),
])
def test_registering_mistakes_are_one_line(registrations_forgotten, name, plugin, message):
    with pytest.raises(QuadnavError, match="^" + re.escape(message)):
        register_planner(name, plugin)


def test_an_unknown_name_lists_the_choices_with_the_registered_ones(registrations_forgotten):
    METHODS.register("minjerk", lambda w, t, s: minimum_derivative(w, t, 3))
    with pytest.raises(QuadnavError, match=r"expected one of minsnap, quintic, .*, minjerk$"):
        TrajectorySettings(method="nosuch")
    trajectory = make_trajectory(np.array([[0, 0, 1], [2, 1, 1], [3, 3, 2.0]]),
                                 TrajectorySettings(method="minjerk"))
    assert trajectory.method == "minjerk"  # the generator's own name
    assert np.allclose(trajectory.position(trajectory.duration), [3, 3, 2])


def install_package(folder: Path, name: str, module: str, entry_points: str) -> None:
    """Install the package ``name`` in ``folder`` as pip would: its module ``name.py``
    (the text ``module``) and a dist-info folder declaring ``entry_points`` (the text of an
    ``entry_points.txt``), found by importlib.metadata once ``folder`` is on the path."""
    (folder / f"{name}.py").write_text(module)
    info = folder / f"{name}-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(entry_points)


def plan_with(folder: Path, planner: str) -> subprocess.CompletedProcess:
    """``quadnav plan`` on a small forest with ``planner``, packages in ``folder`` installed."""
    return subprocess.run(
        [sys.executable, "-m", "quadnav", "plan", "forest:size=10x10x4", "--planner", planner,
         "--iterations", "2000", "--quiet", "-o", str(folder / "out")],
        env={**os.environ, "PYTHONPATH": os.pathsep.join([str(folder), *sys.path])},
        capture_output=True, text=True, timeout=120)


def test_an_installed_packages_entry_point_is_known_to_the_command_line(tmp_path):
    """A package declaring ``[project.entry-points."quadnav.planners"]`` (here a
    dist-info folder on the path, as pip installs one) is a planner of ``quadnav plan``."""
    install_package(tmp_path, "roadmap_plugin",
                    "from quadnav.planning import plan\n\n"
                    "def plan_twice(problem, settings, progress=None):\n"
                    "    return plan(problem, settings, 'rrtstar')\n",
                    "[quadnav.planners]\ntwice = roadmap_plugin:plan_twice\n")
    result = plan_with(tmp_path, "twice")
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "out" / "path.csv").exists()


BROKEN_PACKAGE = ("import no_such_dependency\n\n"
                  "def plan_mine(problem, settings, progress=None):\n"
                  "    pass\n")
BROKEN_ENTRY_POINTS = "[quadnav.planners]\nmine = broken_plugin:plan_mine\n"
BROKEN_LINE = ("planner 'mine' from package entry point broken_plugin:plan_mine could not be "
               "loaded: ModuleNotFoundError: No module named 'no_such_dependency'")


def test_a_broken_installed_plugin_names_itself_and_leaves_the_builtins_alone(
        tmp_path, monkeypatch):
    """An entry point whose module raises as it is imported is listed, and only asking for
    it fails, in one line naming it, its entry point and the error."""
    install_package(tmp_path, "broken_plugin", BROKEN_PACKAGE, BROKEN_ENTRY_POINTS)
    monkeypatch.syspath_prepend(str(tmp_path))
    registry = Registry("planner", "quadnav.planners", {"rrtstar": print})
    assert registry.names() == ["rrtstar", "mine"]
    assert registry.get("rrtstar") is print
    with pytest.raises(PluginError, match="^" + re.escape(BROKEN_LINE) + "$"):
        registry.get("mine")
    with pytest.raises(PluginError, match="^" + re.escape(BROKEN_LINE) + "$"):
        registry.load("mine(speed=1)")


def test_a_broken_installed_plugin_does_not_stop_the_command_line(tmp_path):
    install_package(tmp_path, "broken_plugin", BROKEN_PACKAGE, BROKEN_ENTRY_POINTS)
    result = plan_with(tmp_path, "rrtstar")
    assert result.returncode == 0, result.stderr
    result = plan_with(tmp_path, "mine")
    assert result.returncode == 2
    assert result.stderr.splitlines()[-1] == f"quadnav: error: {BROKEN_LINE}"


def test_a_broken_installed_controller_leaves_the_built_in_ones_flying(tmp_path):
    """Every flight asks which gain sets exist: only the built-in controllers are asked."""
    install_package(tmp_path, "broken_plugin", BROKEN_PACKAGE,
                    "[quadnav.controllers]\nmine = broken_plugin:Mine\n")
    result = subprocess.run(
        [sys.executable, "-m", "quadnav", "track", "hover:duration=1", "--no-figures",
         "--quiet", "-o", str(tmp_path / "out")],
        env={**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), *sys.path])},
        capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr


def test_a_lazy_entry_is_imported_when_first_asked_for_and_a_missing_wheel_is_one_line():
    registry = Registry("thing", "quadnav.no_such_group", {
        "sqrt": "math:sqrt",
        "dist": Lazy("math:dist"),
        "partial": Lazy("functools:partial", (max, 3)),
        "fancy": Lazy("math:sqrt", needs=OptionalWheel("no_such_wheel", "Fancy", "fancy")),
    })
    assert registry.names() == ["sqrt", "dist", "partial", "fancy"]
    assert registry.get("sqrt")(9.0) == 3.0 and registry.get("dist")([0, 0], [3, 4]) == 5.0
    assert registry.get("partial")(1) == 3
    with pytest.raises(PluginError, match=r"^thing 'fancy' needs the optional Fancy wheel: "
                                          r"python -m pip install 'quadnav\[fancy\]'$"):
        registry.get("fancy")


def test_a_name_registered_is_forgotten_by_unregister():
    registry = Registry("thing", "quadnav.no_such_group", {"a": print})
    registry.register("b", len)
    registry.unregister("b")
    assert registry.names() == ["a"]
    with pytest.raises(QuadnavError, match=r"^unknown thing 'b'; expected one of a, or "
                                           r"module:NAME or file.py:NAME$"):
        registry.unregister("b")


def test_worlds_references_and_vehicle_presets_register_as_planners_do(
        registrations_forgotten):
    WORLDS.register("void", empty.GENERATOR)
    assert build_world("void:size=5x5x2").name == "void:size=5x5x2"
    REFERENCES.register("still", REFERENCES.get("hover"))
    assert load_reference("still:height=2").position(0.0).tolist() == [0.0, 0.0, 2.0]
    PRESETS.register("heavy", lambda: load_params("tello").replace(name="heavy", mass=0.1))
    assert load_params("heavy").mass == 0.1 and "heavy" in preset_names()
    assert load_params("heavy") is not load_params("heavy")  # a new one each time
    with pytest.raises(QuadnavError, match=r"^world 'box': expected a Generator, got 3$"):
        WORLDS.register("box", 3)
    with pytest.raises(QuadnavError, match=r"^reference 'box': expected a ReferenceType"):
        REFERENCES.register("box", empty.GENERATOR)


def test_a_registry_loads_entry_points_once_and_keeps_builtins_first():
    registry = Registry("thing", "quadnav.no_such_group", {"a": print, "b": repr})
    registry.register("c", len)
    assert registry.names() == ["a", "b", "c"] and "c" in registry and "d" not in registry
    with pytest.raises(QuadnavError, match=r"^unknown thing 'd'; expected one of a, b, c$"):
        registry.get("d")


#: A controller file that a real stop signal cuts short as it loads: the signal arrives
#: while a class is made, where Python 3.11 wraps the stop in a RuntimeError.
CUT_SHORT = '''\
import os
import signal


class Cut:
    def __set_name__(self, owner, name):
        os.kill(os.getpid(), signal.SIGTERM)
        sum(range(1000))  # the stop is raised here, inside __set_name__


class Follow:
    cut = Cut()
'''


def test_a_stop_while_a_plugin_loads_is_a_stop_not_a_broken_plugin(tmp_path):
    (tmp_path / "cut.py").write_text(CUT_SHORT)
    result = subprocess.run(
        [sys.executable, "-m", "quadnav", "track", "hover:duration=1", "--controller",
         f"{tmp_path / 'cut.py'}:Follow", "--no-figures", "-o", str(tmp_path / "out")],
        capture_output=True, text=True, timeout=120)
    assert (result.returncode, result.stderr) == (143, "quadnav: stopped by SIGTERM\n")
    assert not (tmp_path / "out").exists()
