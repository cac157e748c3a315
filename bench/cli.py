"""Benchmark: whole-process CPU time of the ``quadnav`` command, cold and warm.

Run: ``python bench/cli.py [--repeats 5]``, or ``python bench/cli.py --quick`` (2 repeats).

Each command runs as a subprocess (``python -m quadnav ...``, so the venv's console script
is not needed) in a scratch folder, and its CPU time (user + system, of the process and
its children: ``resource.getrusage(RUSAGE_CHILDREN)`` around it) is measured:

* **cold** — the first run with ``NUMBA_CACHE_DIR`` set to a new, empty directory (one per
  command): every compiled function the command needs is compiled and written there, as
  when it is the first command run after ``pip install``;
* **warm** — the median of ``--repeats`` further runs with that cache.

Commands: ``--version``; ``--help``; ``plan --first --no-refine`` and ``plan`` (the default
budget, then refined) on the default world; ``fly`` on the default world with figures, and
with ``--no-figures``. The baseline, measured in the same run, is ``python -c pass``
(the interpreter's own start-up): each warm figure is also printed as a ratio over it.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

COMMANDS = {
    "--version": ["--version"],
    "--help": ["--help"],
    "plan --first --no-refine": ["plan", "--first", "--no-refine", "--quiet", "-o", "plan"],
    "plan": ["plan", "--quiet", "-o", "plan"],
    "fly --no-figures": ["fly", "--no-figures", "--quiet", "-o", "flight"],
    "fly": ["fly", "--quiet", "-o", "flight"],
}


def cpu_seconds(argv: list[str], folder: Path, cache: Path) -> float:
    """CPU time, s, of one run of ``argv`` in ``folder`` with numba's cache in ``cache``."""
    env = os.environ | {"NUMBA_CACHE_DIR": str(cache), "MPLBACKEND": "Agg"}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(argv, cwd=folder, env=env, check=True, stdout=subprocess.DEVNULL)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--quick", action="store_true", help="2 repeats")
    args = parser.parse_args()
    repeats = 2 if args.quick else args.repeats
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


if __name__ == "__main__":
    main()
