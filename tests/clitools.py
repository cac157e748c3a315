"""Running the ``quadnav`` command as a user runs it, for the CLI tests."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

# The console script installed beside this Python, as a user would run it.
SCRIPT = Path(sys.executable).with_name("quadnav")
QUADNAV = [str(SCRIPT)] if SCRIPT.exists() else [sys.executable, "-m", "quadnav"]


def run(*args: str, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run([*QUADNAV, *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=120)


def assert_user_error(result: subprocess.CompletedProcess, *fragments: str) -> None:
    """Exit 2, exactly one line on stderr containing every fragment, no traceback."""
    assert result.returncode == 2, result
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert "Traceback" not in result.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
