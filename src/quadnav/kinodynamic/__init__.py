"""Kinodynamic planning: trees grown by sampled controls through a robot's motion model.

* :class:`KinoSettings`, :class:`KinoResult` — shared by every model.
"""

from quadnav.kinodynamic.result import KinoResult
from quadnav.kinodynamic.settings import KinoSettings

__all__ = ["KinoResult", "KinoSettings"]
