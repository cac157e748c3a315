"""A trajectory method of your own, in one file: minimum jerk (the piecewise quintic that
minimises the integral of the squared jerk) registered by name and flown through a map.

A method is a function ``method(waypoints (N, 3) m, segment_times (N - 1,) s, settings)
-> Trajectory`` that passes every waypoint at the given times and is at rest at both
ends; quadnav chooses the times, keeps the result within the speed and acceleration
limits and inside the margin (adding waypoints where needed). Use this file as a template.
(A plain class in rotorpy's shape, ``update(t) -> flat outputs``, timed and flown as it is,
needs no registering: examples/plain_trajectory.py.)

Run: python examples/custom_trajectory.py [MAP]   (default: the built-in forest)
"""

import sys

from quadnav.mission import MissionSettings, fly_mission
from quadnav.trajectory import METHODS, TrajectorySettings
from quadnav.trajectory.polynomials.minsnap import minimum_derivative
from quadnav.world import load_world


def minimum_jerk(waypoints, segment_times, settings):
    """The minimum-jerk trajectory through ``waypoints`` at ``segment_times``."""
    return minimum_derivative(waypoints, segment_times, 3)


METHODS.register("minjerk", minimum_jerk)

if __name__ == "__main__":
    world = load_world(sys.argv[1] if len(sys.argv) > 1 else "forest")
    settings = MissionSettings(trajectory=TrajectorySettings(method="minjerk", v_max=2.0))
    metrics = fly_mission(world, settings=settings).metrics()
    print(f"minimum jerk: success {metrics['success']}, trajectory "
          f"{metrics['trajectory_duration_s']:.1f} s, RMS tracking error "
          f"{100 * metrics['rms_tracking_error_m']:.2f} cm, margin kept "
          f"{metrics['trajectory_margin_m']:.3f} m")
