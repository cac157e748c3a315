"""The stages import only the stages before them, and the Tello bridge and emulator not
each other: import-linter's contracts in pyproject.toml hold for the package, and break
for a copy with one import turned round."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "quadnav"

pytest.importorskip("importlinter", reason="import-linter is in quadnav[test]")


def _lint_imports(source: Path, cwd: Path) -> subprocess.CompletedProcess:
    """``lint-imports`` with the project's contract on the package found in ``source``."""
    environment = {**os.environ, "PYTHONPATH": str(source)}
    return subprocess.run([sys.executable, "-c", "from importlinter.cli import lint_imports_command;"
                           " lint_imports_command()", "--no-cache"], cwd=cwd, env=environment,
                          capture_output=True, text=True, timeout=120)


def test_the_stage_order_holds():
    result = _lint_imports(ROOT / "src", ROOT)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "2 kept, 0 broken" in result.stdout


def _lint_imports_with(tmp_path: Path, module: str, line: str) -> subprocess.CompletedProcess:
    """``lint-imports`` on a copy of the package in which ``module`` (a path below
    ``quadnav/``) ends with the import ``line``."""
    shutil.copytree(PACKAGE, tmp_path / "src" / "quadnav",
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path)
    changed = tmp_path / "src" / "quadnav" / module
    changed.write_text(changed.read_text() + f"\n{line}  # noqa\n")
    return _lint_imports(tmp_path / "src", tmp_path)


def test_an_earlier_stage_importing_a_later_one_breaks_the_contract(tmp_path):
    result = _lint_imports_with(tmp_path, "world/model.py", "from quadnav.viz import figures")
    assert result.returncode != 0
    assert "quadnav.world.model -> quadnav.viz.figures" in result.stdout


def test_the_bridge_importing_the_emulator_breaks_the_contract(tmp_path):
    result = _lint_imports_with(tmp_path, "hardware/bridge/landing.py",
                                "from quadnav.hardware.emulator import drone")
    assert result.returncode != 0
    assert "quadnav.hardware.bridge.landing -> quadnav.hardware.emulator.drone" in result.stdout
