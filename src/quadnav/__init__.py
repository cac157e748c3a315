"""quadnav: fly a quadrotor through a known 3D map of box obstacles.

Data flows one way: ``World -> Path -> Trajectory -> Flight -> Report``, one subpackage
per stage (:mod:`quadnav.world`, :mod:`quadnav.planning`, :mod:`quadnav.trajectory`,
:mod:`quadnav.sim`, :mod:`quadnav.report`). The names below are imported on first use,
so ``import quadnav`` is instant and the command line can handle Ctrl-C from its very
first line.
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

#: Public names and the module each comes from, imported on first use.
_LAZY = {
    "MapError": "quadnav.errors",
    "QuadnavError": "quadnav.errors",
    "World": "quadnav.world",
    "load_world": "quadnav.world",
}

__all__ = ["MapError", "QuadnavError", "World", "__version__", "load_world"]


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'quadnav' has no attribute {name!r}")
