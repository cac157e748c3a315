"""Benchmark: whole-process CPU time of the ``quadnav`` command, cold and warm.

Run: ``python bench/cli.py [--repeats 5]``, or ``python bench/cli.py --quick`` (2 repeats).

Each command runs as a subprocess (``python -m quadnav ...``, so the venv's console script
is not needed) in a scratch folder, and its CPU time (user + system, of the process and
its children: ``resource.getrusage(RUSAGE_CHILDREN)`` around it) is measured, with Python
reading and writing its bytecode caches as a user's Python does (``PYTHONDONTWRITEBYTECODE``
is dropped from the environment: without its ``.pyc`` files every run compiles quadnav's
sources again, about 0.3 s of CPU more a run):

* **cold** — the first run with ``NUMBA_CACHE_DIR`` set to a new, empty directory (one per
  command): every compiled function the command needs is compiled and written there, as
  when it is the first command run after ``pip install``;
* **warm** — the median of ``--repeats`` further runs with that cache;
* **after pip install** — the first ``fly`` of a fresh install: this checkout (copied, so
  no earlier build folder is reused) is built into a wheel as ``pip install .`` builds it,
  which compiles the kernels into it (``setup.py``; the build's CPU is printed too), the
  wheel is installed into a scratch folder, and ``fly`` runs from there with numba's
  default cache locations.

Commands: ``--version``; ``--help``; ``plan --first --no-refine`` (with and without
``plan.png``) and ``plan`` (the default budget, then refined) on the default world; ``fly``
on the default world with figures, and with ``--no-figures``. The baseline, measured in the
same run, is ``python -c pass`` (the interpreter's own start-up): each warm figure is also
printed as a ratio over it.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import tomllib
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from packaging.requirements import Requirement

REPO = Path(__file__).resolve().parents[1]
COMMANDS = {
    "--version": ["--version"],
    "--help": ["--help"],
    "plan --first --no-refine": ["plan", "--first", "--no-refine", "--quiet", "-o", "plan"],
    "plan --first --no-refine --no-figures": ["plan", "--first", "--no-refine", "--no-figures",
                                              "--quiet", "-o", "plan"],
    "plan": ["plan", "--quiet", "-o", "plan"],
    "fly --no-figures": ["fly", "--no-figures", "--quiet", "-o", "flight"],
    "fly": ["fly", "--quiet", "-o", "flight"],
}


def cpu_seconds(argv: list[str], folder: Path, cache: Path | None,
                **variables: str) -> float:
    """CPU time, s, of one run of ``argv`` in ``folder`` with numba's cache in ``cache``
    (None: numba's default places) and the extra environment ``variables``."""
    env = {name: value for name, value in os.environ.items()
           if name not in ("NUMBA_CACHE_DIR", "PYTHONDONTWRITEBYTECODE")}
    env |= {"MPLBACKEND": "Agg", **variables}
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = str(cache)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(argv, cwd=folder, env=env, check=True, stdout=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def missing_build_requirements() -> list[str]:
    """The requirements of pyproject.toml's ``[build-system]`` that this environment does
    not meet (the wheel is built here without build isolation)."""
    requires = tomllib.loads((REPO / "pyproject.toml").read_text())["build-system"]["requires"]
    missing = []
    for text in requires:
        requirement = Requirement(text)
        try:
            if version(requirement.name) in requirement.specifier:
                continue
        except PackageNotFoundError:
            pass
        missing.append(text)
    return missing


def after_pip_install(scratch: Path) -> tuple[float, float]:
    """CPU seconds of building this checkout's wheel (kernels compiled in) and of the first
    ``quadnav fly`` of that wheel installed into ``scratch``."""
    source, site = scratch / "source", scratch / "site"
    shutil.copytree(REPO, source, ignore=shutil.ignore_patterns(
        ".git", "build", "*.egg-info", "__pycache__", "site"))
    pip = [sys.executable, "-m", "pip", "-q"]
    # Without build isolation the kernels are compiled by this environment's numba, the
    # one that loads them (an isolated build fetches the newest, the same on a fresh venv).
    build = cpu_seconds([*pip, "wheel", "--no-deps", "--no-build-isolation", "-w",
                         str(scratch / "wheel"), str(source)], scratch, None)
    wheel = next((scratch / "wheel").glob("quadnav-*.whl"))
    subprocess.run([*pip, "install", "--no-deps", "--target", str(site), str(wheel)],
                   check=True)
    first = cpu_seconds([sys.executable, "-m", "quadnav", "fly", "--quiet", "-o", "flight"],
                        scratch, None, PYTHONPATH=str(site))
    return build, first


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--quick", action="store_true", help="2 repeats")
    args = parser.parse_args()
    repeats = 2 if args.quick else args.repeats
    if missing := missing_build_requirements():
        parser.error("the wheel is built in this environment, which lacks its build "
                     f"requirements: pip install {' '.join(repr(m) for m in missing)}")
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        baseline = statistics.median(cpu_seconds([sys.executable, "-c", "pass"], folder,
                                                 folder / "cache") for _ in range(repeats))
        print(f"baseline: python -c pass, {baseline:.3f} s CPU (median of {repeats})")
        print("| command | cold CPU s | warm CPU s (median) | warm / python -c pass |")
        print("|---|---|---|---|")
        for number, (label, command) in enumerate(COMMANDS.items()):
            argv, cache = [sys.executable, "-m", "quadnav", *command], folder / f"cache{number}"
            cold = cpu_seconds(argv, folder, cache)
            warm = statistics.median(cpu_seconds(argv, folder, cache) for _ in range(repeats))
            print(f"| `quadnav {label}` | {cold:.2f} | {warm:.2f} | {warm / baseline:.0f}x |",
                  flush=True)
        build, first = after_pip_install(folder)
        print(f"\nafter pip install: building the wheel (kernels compiled in) {build:.1f} s "
              f"CPU; the first `quadnav fly` of the installed wheel {first:.2f} s CPU")


if __name__ == "__main__":
    main()
