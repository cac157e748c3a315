"""The kernels compiled while ``pip install`` builds the wheel (setup.py, quadnav.cli.precompile)
are installed with the package, and the main job loads them instead of compiling.

These tests look at the installed package itself, so they run where it was installed from a
wheel (``pip install .``, as the README and CI do) and skip in an editable install, which
compiles nothing at install time."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from installed import MAIN_KERNELS, carried, editable

from_wheel = pytest.mark.skipif(
    editable(), reason="quadnav is installed in editable mode: its build compiles no "
                        "kernels (numba caches them beside the sources on the first run)")


def _cache_lines(arguments: list[str], folder, cache_dir: bool = False) -> str:
    """What numba says of its cache (``NUMBA_DEBUG_CACHE``) while ``quadnav ARGUMENTS`` runs
    in ``folder``, which must succeed; with the cache beside the package unless ``cache_dir``
    (then where ``NUMBA_CACHE_DIR`` says, if set, as for this process)."""
    environment = {name: value for name, value in os.environ.items()
                   if cache_dir or name != "NUMBA_CACHE_DIR"} | {"NUMBA_DEBUG_CACHE": "1"}
    done = subprocess.run([sys.executable, "-m", "quadnav", *arguments], cwd=folder,
                          env=environment, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return done.stdout


@from_wheel
def test_the_wheel_carries_the_main_kernels_compiled():
    for kernel in MAIN_KERNELS:
        assert carried(kernel), f"{kernel} was not compiled into the wheel"


@from_wheel
def test_the_main_job_loads_its_kernels_and_compiles_none(tmp_path):
    said = _cache_lines(["fly", "--no-figures", "--quiet", "-o", "flight"], tmp_path)
    assert "[cache] data loaded" in said
    assert "[cache] data saved" not in said


@from_wheel
def test_the_first_plain_python_flight_loads_its_step_and_compiles_none(tmp_path):
    from quadnav.cli.precompile import PLAIN

    said = _cache_lines(PLAIN, tmp_path)
    assert "held.held_step" in said and "[cache] data loaded" in said
    assert "[cache] data saved" not in said


def test_the_plain_python_flight_of_the_build_flies_and_numba_serves_its_step(tmp_path):
    from quadnav.cli.precompile import PLAIN
    from quadnav.control.held import held_step
    from quadnav.control.registry import make_controller
    from quadnav.sim.flight import Ending
    from quadnav.sim.simulate import simulate
    from quadnav.trajectory.references.builtin import load_reference
    from quadnav.vehicle.params import load_params

    tello = load_params("tello")
    controller = make_controller(PLAIN[PLAIN.index("--controller") + 1], tello)
    flight = simulate(load_reference(PLAIN[1]), tello, controller=controller)
    assert flight.ending is Ending.COMPLETED  # held_step compiled into the cache, or loaded
    assert held_step.stats.cache_path is not None, "held_step is not cached (cache=True)"
    said = [line for line in _cache_lines(PLAIN, tmp_path, cache_dir=True).splitlines()
            if "held.held_step" in line]  # another process: numba's cache serves the step
    assert any(line.startswith("[cache] data loaded") for line in said), said
    assert not any(line.startswith("[cache] data saved") for line in said), said


def test_a_failed_compile_command_is_reported_with_its_last_lines(tmp_path, capsys):
    from quadnav.cli.precompile import finish, start

    failed = start(["plan", "no-such-map.txt", "--quiet", "-o", "plan"], tmp_path)
    assert finish(failed) is False
    header, *tail = capsys.readouterr().err.splitlines()
    assert header.startswith("quadnav precompile: ") and header.endswith(" exited 2")
    assert "-m quadnav plan no-such-map.txt" in header
    assert any("no-such-map.txt" in line for line in tail)
    assert not (tmp_path / "plan").exists()
