"""Compile the kernels of the main commands into numba's cache beside the package.

The build runs this (``setup.py``), so that the first ``quadnav fly`` after ``pip install``
loads the planner, the controllers and the simulation from the cache instead of compiling
them first. numba keys its cache on the content of each source file
(numba 0.68 and later), the Python version, numba's version and the CPU, so the kernels
compiled into the wheel while ``pip install`` builds it on this machine are the ones the
installed package loads. Where a key differs (an older numba, a wheel built on another
machine, ``NUMBA_CACHE_DIR`` set), nothing breaks: the first run compiles as before.

``python -m quadnav.cli.precompile`` runs, quietly in a scratch folder, ``quadnav plan``
and then ``quadnav map info`` on the default world (and, in this process, the exact
checks reached only when something is in the way: :func:`compile_checks_in_the_way`)
beside ``quadnav track hover`` with each controller (each has a step of its own and a
compiled loop of its own for its type of gains) and then with a plain-Python controller
(:class:`Follow`: every plain-Python controller flies by one compiled step,
:func:`quadnav.control.held.held_step`, in the cascade's loop), two chains side by side
so that two cores compile at once; then ``quadnav fly --no-figures``, which loads what
they compiled and compiles the rest. It exits 1, with the failing command's last lines
on stderr, if a command fails.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from quadnav.arrays import FloatArray
from quadnav.control.registry import CONTROLLERS
from quadnav.world.builtin import DEFAULT_WORLD_SPEC

#: The planner's kernels (the default world, the default budget, then refined).
PLAN = ["plan", "--no-figures", "--quiet", "-o", "plan"]


class Follow:
    """A plain-Python controller in rotorpy's shape: the reference's velocity plus 1/s times
    its position error, commanded as a velocity (rotorpy's ``cmd_vel``) that the cascade's
    loops fly. Flown by :data:`PLAIN`, it compiles the step of every plain-Python
    controller."""

    control_abstraction = "cmd_vel"

    def __init__(self, quad_params: dict) -> None:
        """Built with the vehicle's rotorpy parameter dict, which it does not need."""

    def update(self, t: float, state: dict, flat_output: dict) -> dict[str, FloatArray]:
        """The velocity command (3,) m/s at ``t`` s, as ``cmd_v``."""
        return {"cmd_v": flat_output["x_dot"] + (flat_output["x"] - state["x"])}


def track(controller: str, folder: str | None = None, reference: str = "hover") -> list[str]:
    """The arguments of ``reference`` flown with ``controller`` into ``folder`` (default
    ``track-CONTROLLER``): the simulation's kernels."""
    return ["track", reference, "--controller", controller, "--no-figures", "--quiet",
            "-o", folder or f"track-{controller}"]


#: A short hover flown by :class:`Follow` (it calls Python at every control step).
PLAIN = track("quadnav.cli.precompile:Follow", "track-plain", "hover:duration=1")


#: The default world's facts, after the planner: the exact free volume's kernels (about
#: 6.5 s of CPU to compile, which ``quadnav map info`` would otherwise spend on its first
#: run).
INFO = ["map", "info", DEFAULT_WORLD_SPEC]

#: The whole main job, last: it compiles what neither of the others did.
FLY = ["fly", "--no-figures", "--quiet", "-o", "fly"]


def start(arguments: Sequence[str], folder: Path) -> subprocess.Popen[bytes]:
    """Start ``quadnav ARGUMENTS`` in ``folder`` with this interpreter."""
    return subprocess.Popen([sys.executable, "-m", "quadnav", *arguments], cwd=folder,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


def finish(process: subprocess.Popen[bytes]) -> bool:
    """Wait for ``process``; on failure print its command and last lines; True if it ran."""
    _, errors = process.communicate()
    if process.returncode == 0:
        return True
    tail = errors.decode(errors="replace").strip().splitlines()[-5:]
    print(f"quadnav precompile: {' '.join(map(str, process.args))} exited "
          f"{process.returncode}", *tail, sep="\n  ", file=sys.stderr)
    return False


def run_in_sequence(commands: Sequence[Sequence[str]], folder: Path) -> bool:
    """Run ``commands`` one after another in one process each; True if all ran (a failed
    one does not stop the others: what they compile is kept all the same)."""
    return all([finish(start(command, folder)) for command in commands])


def compile_checks_in_the_way() -> None:
    """Compile, in this process, the exact checks the commands reach only when something
    is in the way or too large: the first contact along a segment (a path's fault, a
    collision, a leg's end: :meth:`~quadnav.world.World.first_hit`), the free volume
    estimated over points (a map too costly to measure exactly), and a point's check as
    OMPL's planners ask it."""
    from quadnav.world import load_world
    from quadnav.world.blockgrid import grid_point_free

    world = load_world(DEFAULT_WORLD_SPEC)
    world.first_hit(world.lower, world.upper)
    world.free_volume(budget=0)
    grid_point_free(*world.lower, world.block_grid)


def planning_chain(folder: Path) -> bool:
    """:data:`PLAN` and :data:`INFO` in ``folder`` one after the other, then
    :func:`compile_checks_in_the_way`; True if both commands ran."""
    ran = run_in_sequence([PLAN, INFO], folder)
    compile_checks_in_the_way()
    return ran


def main() -> int:
    """Compile the kernels; exit code 0, or 1 if a command failed."""
    with tempfile.TemporaryDirectory(prefix="quadnav-precompile-") as scratch:
        folder = Path(scratch)
        with ThreadPoolExecutor(max_workers=2) as chains:
            planning = chains.submit(planning_chain, folder)
            flying = run_in_sequence([*(track(name) for name in CONTROLLERS), PLAIN], folder)
            planned = planning.result()
        return 0 if planned and flying and finish(start(FLY, folder)) else 1


if __name__ == "__main__":
    sys.exit(main())
