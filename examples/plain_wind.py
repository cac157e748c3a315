"""A plain-Python wind in rotorpy's shape, in one file: a gust front that arrives at
``start`` s and builds up over ``rise`` s, blowing harder with height up to ``height`` m.

A wind is a class built with keyword arguments of its own, with
``update(t, position) -> wind velocity (3,)`` in m/s, world frame (rotorpy's
``wind_template.py``). quadnav asks it at the vehicle's position once per control step, and
the vehicle's drag acts on its airspeed (its velocity less the wind's), beside the steady
force and the gusts. Use this file as a template; the command line flies it too::

    quadnav fly --wind "examples/plain_wind.py:GustFront(speed=4.0)"

Run: python examples/plain_wind.py [MAP]   (a map with its own start and goal; default:
the built-in forest)
"""

import sys

import numpy as np

from quadnav.mission import MissionSettings, fly_mission
from quadnav.sim.settings import SimSettings
from quadnav.world import load_world


class GustFront:
    """``speed`` m/s along ``direction`` from ``start`` s (reached after ``rise`` s), in
    proportion to the height up to ``height`` m."""

    def __init__(self, speed=4.0, direction=(1.0, 0.0, 0.0), start=2.0, rise=1.0,
                 height=2.0):
        self.wind = speed * np.asarray(direction, dtype=float)
        self.start, self.rise, self.height = start, rise, height

    def update(self, t, position):
        arrived = min(max((t - self.start) / self.rise, 0.0), 1.0)
        aloft = min(max(position[2] / self.height, 0.0), 1.0)
        return arrived * aloft * self.wind


if __name__ == "__main__":
    place = sys.argv[1] if len(sys.argv) > 1 else "forest"
    world = load_world(place)
    for name, wind in (("still air", None), ("gust front", f"{__file__}:GustFront(speed=4.0)")):
        settings = MissionSettings(sim=SimSettings(wind_model=wind))
        mission = fly_mission(world, settings=settings)  # from its own start to its goal
        print(f"{name} in {place}: success {mission.success}, RMS tracking error "
              f"{100 * mission.flight.rms_tracking_error:.2f} cm")
