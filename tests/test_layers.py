"""The stages import only the stages before them, and the rooms that must stay apart do:
import-linter's contracts in pyproject.toml hold for the package, and break for a copy with
imports turned round."""

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
    assert "6 kept, 0 broken" in result.stdout


def test_an_earlier_stage_importing_a_later_one_breaks_the_contracts(tmp_path):
    shutil.copytree(PACKAGE, tmp_path / "src" / "quadnav",
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path)
    turned = {"world/model.py": "quadnav.viz.figures",  # the layers
              "control/se3.py": "quadnav.world.model",  # a controller that knows maps
              "kinoflight.py": "quadnav.tracking",  # independence
              "batch/table.py": "quadnav.hardware",
              "tune/space.py": "quadnav.hardware",
              "hardware/bridge/landing.py": "quadnav.hardware.emulator.drone"}
    for file, module in turned.items():
        path = tmp_path / "src" / "quadnav" / file
        path.write_text(path.read_text() + f"\nimport {module}  # noqa\n")
    result = _lint_imports(tmp_path / "src", tmp_path)
    assert result.returncode != 0
    assert "0 kept, 6 broken" in result.stdout, result.stdout
    for file, module in turned.items():
        importer = "quadnav." + file.removesuffix(".py").replace("/", ".")
        assert f"{importer} -> {module}" in result.stdout, (importer, result.stdout)
