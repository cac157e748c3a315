"""Fly the whole pipeline (plan, refine, trajectory, closed loop) and print the metrics.

Run: python examples/fly.py [MAP]    (default: the built-in window world)
"""

import sys

from quadnav.mission import MissionSettings, fly_mission
from quadnav.trajectory import TrajectorySettings
from quadnav.world import load_world

world = load_world(sys.argv[1] if len(sys.argv) > 1 else "window")
settings = MissionSettings(trajectory=TrajectorySettings(v_max=2.0, a_max=3.0))
mission = fly_mission(world, settings=settings)  # the map's start, goal and margin
metrics = mission.metrics()
print(f"success {metrics['success']}, flight {metrics['flight_time_s']:.1f} s, "
      f"RMS tracking error {100 * metrics['rms_tracking_error_m']:.2f} cm, "
      f"margin kept {metrics['flight_margin_m']:.3f} m")
