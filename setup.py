"""The build step that is not configuration (the rest is in ``pyproject.toml``): after the
sources are copied into the build folder, compile quadnav's numba kernels there
(:mod:`quadnav.cli.precompile`), so the wheel carries them in its ``__pycache__`` folders
and the first ``quadnav fly`` after ``pip install`` loads them instead of compiling.

Set ``QUADNAV_PRECOMPILE=0`` to skip it (the first run then compiles, about 30 s of CPU).
Editable installs skip it: numba caches beside the sources on the first run. A failed
compile is reported and does not fail the build.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py


class BuildPyWithKernels(build_py):
    """``build_py``, then the kernels compiled into the build folder's package."""

    def run(self) -> None:
        super().run()
        if self.editable_mode or os.environ.get("QUADNAV_PRECOMPILE") == "0":
            return
        build_lib = Path(self.build_lib).resolve()
        # pip's isolated build environment is on PYTHONPATH: keep it, after the build.
        path = os.pathsep.join(filter(None, [str(build_lib), os.environ.get("PYTHONPATH")]))
        environment = {name: value for name, value in os.environ.items()
                       if name != "NUMBA_CACHE_DIR"}  # numba caches beside the sources
        environment |= {"PYTHONPATH": path, "PYTHONDONTWRITEBYTECODE": "1"}
        print("compiling quadnav's kernels into the build (about 40 s of CPU)", flush=True)
        done = subprocess.run([sys.executable, "-m", "quadnav.cli.precompile"],
                              env=environment, check=False)
        if done.returncode != 0:
            print("quadnav: the kernels were not compiled into the build; the first run "
                  "compiles them", file=sys.stderr)


setup(cmdclass={"build_py": BuildPyWithKernels})
