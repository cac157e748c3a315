"""quadnav: fly a quadrotor through a known 3D map of box obstacles.

Data flows one way: ``World -> Path -> Trajectory -> Flight -> Report``.
This release provides the first stage, :mod:`quadnav.world`: map files, exact
geometry and built-in worlds.
"""

from quadnav.errors import MapError, QuadnavError
from quadnav.world import World, load_world

__version__ = "0.1.0"

__all__ = ["MapError", "QuadnavError", "World", "__version__", "load_world"]
