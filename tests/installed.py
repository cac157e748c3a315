"""How quadnav is installed here: from a wheel, whose build compiled the main commands'
kernels into numba's cache beside the package (setup.py), or editable, which compiles
nothing at install time."""

from __future__ import annotations

import json
import os
from importlib import metadata

#: Kernels of each stage the main job runs: the planner, the controller, the loop; the
#: step every plain-Python controller flies by; the free volume of ``map info``, exact and
#: estimated; and the first contact along a segment (a path's fault, a collision).
MAIN_KERNELS = ("rrtstar_kernel.grow", "refine_kernel.smoothing_sweeps", "cascade.control",
                "se3.se3_step", "loop.fly_steps", "held.held_step", "volume._measure",
                "blockgrid.grid_points_free", "geometry.first_hits")


def editable() -> bool:
    """Whether quadnav is installed in editable mode (``pip install -e .``)."""
    direct_url = metadata.distribution("quadnav").read_text("direct_url.json")
    return bool(direct_url and json.loads(direct_url).get("dir_info", {}).get("editable"))


def carried(kernel: str) -> bool:
    """Whether the installed package carries numba's cache of ``kernel``
    (``module.function``, as numba names its files): an index (.nbi) and a data (.nbc)
    file."""
    files = [str(path) for path in metadata.files("quadnav") or []
             if f"__pycache__/{kernel}-" in str(path)]
    return any(path.endswith(".nbi") for path in files) and any(
        path.endswith(".nbc") for path in files)


def main_kernels_installed() -> bool:
    """Whether quadnav was installed from a wheel that carries every kernel of
    :data:`MAIN_KERNELS` compiled where numba looks for them: for this CPU, in the cache
    beside the package (not with ``NUMBA_CPU_NAME`` or ``NUMBA_CACHE_DIR`` set, as for the
    CI's run on a generic CPU)."""
    if os.environ.get("NUMBA_CPU_NAME") or os.environ.get("NUMBA_CACHE_DIR"):
        return False
    return not editable() and all(map(carried, MAIN_KERNELS))
