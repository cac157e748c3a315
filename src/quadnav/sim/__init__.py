"""Flight stage: fly a trajectory in closed loop on the simulated vehicle.

* :func:`simulate` — trajectory, vehicle, gains, world -> :class:`Flight`.
* :class:`SimSettings` — rates, settling time, goal tolerance, wind, noise, seed.
* :class:`Flight` — the record, how it ended (:class:`Ending`) and tracking statistics.
"""

from quadnav.sim.flight import Ending, Flight
from quadnav.sim.settings import SimSettings
from quadnav.sim.simulate import simulate

__all__ = ["Ending", "Flight", "SimSettings", "simulate"]
