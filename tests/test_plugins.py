"""Plug-in points by name: planners and trajectory methods registered in a process or
declared by an installed package's entry points, and the mistakes a user can make."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import numpy as np
import pytest

from quadnav.errors import QuadnavError
from quadnav.planning import make_problem, plan, planner_names, register_planner
from quadnav.planning.registry import PLANNERS
from quadnav.plugins import Registry
from quadnav.trajectory.generate import METHODS, TrajectorySettings, make_trajectory
from quadnav.trajectory.polynomials.minsnap import minimum_derivative
from quadnav.world import load_world


@pytest.fixture
def registries():
    """The planner and method registries as they were, put back afterwards."""
    saved = [(registry, dict(registry._all())) for registry in (PLANNERS, METHODS)]
    yield
    for registry, plugins in saved:
        registry._plugins = plugins


def test_a_registered_planner_is_planned_with_by_name(registries):
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
def test_registering_mistakes_are_one_line(registries, name, plugin, message):
    with pytest.raises(QuadnavError, match="^" + re.escape(message)):
        register_planner(name, plugin)


def test_an_unknown_name_lists_the_choices_with_the_registered_ones(registries):
    METHODS.register("minjerk", lambda w, t, s: minimum_derivative(w, t, 3))
    with pytest.raises(QuadnavError, match=r"expected one of minsnap, quintic, .*, minjerk$"):
        TrajectorySettings(method="nosuch")
    trajectory = make_trajectory(np.array([[0, 0, 1], [2, 1, 1], [3, 3, 2.0]]),
                                 TrajectorySettings(method="minjerk"))
    assert trajectory.method == "minjerk"  # the generator's own name
    assert np.allclose(trajectory.position(trajectory.duration), [3, 3, 2])


def test_an_installed_packages_entry_point_is_known_to_the_command_line(tmp_path):
    """A package declaring ``[project.entry-points."quadnav.planners"]`` (here a
    dist-info folder on the path, as pip installs one) is a planner of ``quadnav plan``."""
    (tmp_path / "roadmap_plugin.py").write_text(
        "from quadnav.planning import plan\n\n"
        "def plan_twice(problem, settings, progress=None):\n"
        "    return plan(problem, settings, 'rrtstar')\n")
    info = tmp_path / "roadmap_plugin-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: roadmap-plugin\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(
        "[quadnav.planners]\ntwice = roadmap_plugin:plan_twice\n")
    environment = {**os.environ, "PYTHONPATH": str(tmp_path)}
    result = subprocess.run(
        [sys.executable, "-m", "quadnav", "plan", "forest:size=10x10x4", "--planner", "twice",
         "--iterations", "2000", "--quiet", "-o", str(tmp_path / "out")],
        env=environment, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "out" / "path.csv").exists()


def test_a_registry_loads_entry_points_once_and_keeps_builtins_first():
    registry = Registry("thing", "quadnav.no_such_group", {"a": print, "b": repr})
    registry.register("c", len)
    assert registry.names() == ["a", "b", "c"] and "c" in registry and "d" not in registry
    with pytest.raises(QuadnavError, match=r"^unknown thing 'd'; expected one of a, b, c$"):
        registry.get("d")
