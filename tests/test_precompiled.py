"""The kernels compiled while ``pip install`` builds the wheel (setup.py, quadnav.cli.precompile)
are installed with the package, and the main job loads them instead of compiling.

These tests look at the installed package itself, so they run where it was installed from a
wheel (``pip install .``, as the README and CI do) and skip in an editable install, which
compiles nothing at install time."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from importlib import metadata

import pytest


def _editable() -> bool:
    direct_url = metadata.distribution("quadnav").read_text("direct_url.json")
    return bool(direct_url and json.loads(direct_url).get("dir_info", {}).get("editable"))


from_wheel = pytest.mark.skipif(
    _editable(), reason="quadnav is installed in editable mode: its build compiles no "
                        "kernels (numba caches them beside the sources on the first run)")

#: Kernels of each stage the main job runs: the planner, the controller, the loop.
MAIN_KERNELS = ("rrtstar_kernel.grow", "refine_kernel.smoothing_sweeps", "cascade.control",
                "se3.se3_step", "loop.fly_steps")


@from_wheel
def test_the_wheel_carries_the_main_kernels_compiled():
    installed = [str(path) for path in metadata.files("quadnav")]
    for kernel in MAIN_KERNELS:
        index = [path for path in installed
                 if f"__pycache__/{kernel}-" in path and path.endswith(".nbi")]
        data = [path for path in installed
                if f"__pycache__/{kernel}-" in path and path.endswith(".nbc")]
        assert index and data, f"{kernel} was not compiled into the wheel"


@from_wheel
def test_the_main_job_loads_its_kernels_and_compiles_none(tmp_path):
    environment = {name: value for name, value in os.environ.items()
                   if name != "NUMBA_CACHE_DIR"} | {"NUMBA_DEBUG_CACHE": "1"}
    done = subprocess.run([sys.executable, "-m", "quadnav", "fly", "--no-figures", "--quiet",
                           "-o", "flight"], cwd=tmp_path, env=environment,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "[cache] data loaded" in done.stdout
    assert "[cache] data saved" not in done.stdout


def test_a_failed_compile_command_is_reported_with_its_last_lines(tmp_path, capsys):
    from quadnav.cli.precompile import finish, start

    failed = start(["plan", "no-such-map.txt", "--quiet", "-o", "plan"], tmp_path)
    assert finish(failed) is False
    header, *tail = capsys.readouterr().err.splitlines()
    assert header.startswith("quadnav precompile: ") and header.endswith(" exited 2")
    assert "-m quadnav plan no-such-map.txt" in header
    assert any("no-such-map.txt" in line for line in tail)
    assert not (tmp_path / "plan").exists()
