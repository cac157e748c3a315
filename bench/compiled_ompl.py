"""Compiled OMPL RRT* (``bench/ompl_rrtstar.cpp``) for the planning bench.

The C++ driver is built on first use with ``g++`` against Debian's ``libompl-dev``
(``apt install libompl-dev``) into ``bench/build/``, and rebuilt when its source is newer.
:func:`compiled_ompl` says why it cannot be used where the headers or a compiler are
missing, so the bench can leave its column out with that reason.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

from quadnav.planning import PlannerSettings, PlanningProblem, path_length

HERE = Path(__file__).resolve().parent
SOURCE = HERE / "ompl_rrtstar.cpp"
BINARY = HERE / "build" / "ompl_rrtstar"
#: Where Debian's libompl-dev puts OMPL 1.5's headers, and Eigen's, which they include.
INCLUDES = (Path("/usr/include/ompl-1.5"), Path("/usr/include/eigen3"))


@dataclass(frozen=True)
class FirstRun:
    """A run stopped at its first solution (of any planner of the bench): the time to it
    and the set-up outside the clock, s (``nan``: not measured), and the full path's
    length, m (``inf``: none found in time)."""

    first: float
    setup: float
    length: float


def compiled_ompl() -> tuple[Path | None, str]:
    """The built driver and ``""``, or ``None`` and why it cannot be built here."""
    missing = [str(p) for p in INCLUDES if not p.is_dir()]
    if missing:
        return None, f"{' and '.join(missing)} not found (apt install libompl-dev)"
    compiler = shutil.which("g++")
    if compiler is None:
        return None, "no g++ to build bench/ompl_rrtstar.cpp"
    if BINARY.is_file() and BINARY.stat().st_mtime >= SOURCE.stat().st_mtime:
        return BINARY, ""
    BINARY.parent.mkdir(exist_ok=True)
    # Built under a name of this process's own, then renamed: two processes building at
    # once never run a half-written binary.
    partial = BINARY.with_name(f"{BINARY.name}.{os.getpid()}")
    command = [compiler, "-O2", "-DNDEBUG", "-std=c++17",
               *(f"-I{p}" for p in INCLUDES), str(SOURCE), "-o", str(partial), "-lompl"]
    built = subprocess.run(command, capture_output=True, text=True, check=False)
    if built.returncode != 0:
        errors = [line for line in built.stderr.splitlines() if "error" in line]
        return None, f"g++ failed: {(errors or ['no message'])[0]}"
    partial.replace(BINARY)
    return BINARY, ""


def write_problem(problem: PlanningProblem, settings: PlannerSettings, file: Path) -> None:
    """Write the driver's problem file: the inflated boundary and blocks, the search's
    start and goal, and our step, goal bias and rewire factor (see the .cpp header)."""
    world = problem.free_world
    numbers = [*world.lower, *world.upper, *problem.search_start, *problem.search_goal,
               settings.step_for(world), settings.goal_bias, settings.rewire_factor,
               len(world.blocks)]
    rows = [" ".join(f"{v:.17g}" for v in numbers)]
    rows += [" ".join(f"{v:.17g}" for v in block) for block in world.blocks]
    file.write_text("\n".join(rows) + "\n", encoding="utf-8")


def run_compiled(binary: Path, problem_file: Path, problem: PlanningProblem, seed: int,
                 limit: float) -> FirstRun:
    """Run the driver once with OMPL's seed ``seed + 1`` (it must be nonzero) until its
    first solution or ``limit`` seconds."""
    done = subprocess.run([str(binary), str(problem_file), str(seed + 1), f"{limit:g}"],
                          capture_output=True, text=True, check=True)
    setup, first, search_length, _vertices = done.stdout.split()
    legs = path_length(problem.start_leg) + path_length(problem.goal_leg)
    length = float(search_length) + legs
    return FirstRun(float(first), float(setup), length)  # both "inf" when none found
