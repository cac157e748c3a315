"""Running the ``quadnav`` command as a user runs it, for the CLI tests.

:func:`run` starts the installed console script in a new process, as a user does.
:func:`run_here` runs the same command line in this process, for tables of bad inputs:
a new process spends about a second loading the compiled kernels before it reads a
flag, and the answer (exit code, stdout, stderr) is the same.
"""

from __future__ import annotations

import contextlib
import functools
import io
import os
import subprocess
import sys
import warnings
from pathlib import Path

# The console script installed beside this Python, as a user would run it.
SCRIPT = Path(sys.executable).with_name("quadnav")
QUADNAV = [str(SCRIPT)] if SCRIPT.exists() else [sys.executable, "-m", "quadnav"]


def run(*args: str, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run([*QUADNAV, *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=120)


def run_here(*args: str, cwd=None) -> subprocess.CompletedProcess:
    """``quadnav args`` run in this process (see the module docstring); warnings print as
    in a new process, once each, in quadnav's one-line form."""
    from quadnav.cli import main as cli

    out, err = io.StringIO(), io.StringIO()
    parser = _parser()
    shown, here, build = warnings.showwarning, os.getcwd(), cli.build_parser
    cli.build_parser = lambda argv=None: parser
    try:
        if cwd is not None:
            os.chdir(cwd)
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
                warnings.catch_warnings():
            warnings.simplefilter("default")
            try:
                code = cli.main([str(a) for a in args])
            except SystemExit as stop:
                code = stop.code
    finally:
        warnings.showwarning, cli.build_parser = shown, build
        os.chdir(here)
    return subprocess.CompletedProcess(args, code, out.getvalue(), err.getvalue())


@functools.cache
def _parser():
    """One parser for every in-process run: building it takes most of a short run."""
    from quadnav.cli.main import build_parser

    return build_parser()



def assert_user_error(result: subprocess.CompletedProcess, *fragments: str) -> None:
    """Exit 2, exactly one line on stderr containing every fragment, no traceback."""
    assert result.returncode == 2, result
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert "Traceback" not in result.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
