"""A trajectory of your own as a plain class in rotorpy's shape, in one file: stop and go
along the planned path, named on the command line where it is, unregistered:

    quadnav fly course:rotorpy/double_pillar --start -1.1 -3 1 --goal -1.1 3 1.5 \\
        --reference "examples/plain_trajectory.py:StopAndGo(speed=1.5)"
    quadnav track "examples/plain_trajectory.py:StopAndGo(points=[[0, 0, 1], [2, 0, 1]])"

A trajectory class has ``update(t) -> dict`` of flat outputs (rotorpy's
``traj_template.py``): ``x``, ``x_dot``, ``x_ddot`` ((3,) m, m/s, m/s^2) and ``yaw``,
``yaw_dot`` (rad, rad/s) are flown. ``fly`` builds it with the planned path as
``points`` (N, 3) when its constructor takes ``points``, and flies it for its
``duration`` (or rotorpy's ``t_keyframes[-1]``, or ``--duration``). quadnav samples it at
the control rate and measures the margin it keeps exactly. rotorpy's own classes
(``rotorpy.trajectories.minsnap:MinSnap``, ...) fly the same way. To add a method that
quadnav times and keeps inside the margin itself, register it instead:
examples/custom_trajectory.py.

Run: python examples/plain_trajectory.py [SPEED]   (default 1.5 m/s; flies double_pillar)
"""

import sys

import numpy as np


class StopAndGo:
    """Each straight segment of ``points`` (N, 3) m flown from rest to rest by a quintic
    smoothstep peaking at ``speed`` m/s: the vehicle stays on the path, so the reference
    keeps the margin the path keeps."""

    def __init__(self, points, speed=1.0):
        self.points = np.asarray(points, dtype=float)
        lengths = np.linalg.norm(np.diff(self.points, axis=0), axis=1)
        self.segment_times = 1.875 * lengths / speed  # the smoothstep peaks at 1.875 L / T
        self.starts = np.concatenate([[0.0], np.cumsum(self.segment_times)])
        self.duration = self.starts[-1]

    def update(self, t):
        k = int(np.clip(np.searchsorted(self.starts, t, side="right") - 1, 0,
                        len(self.segment_times) - 1))
        time = self.segment_times[k]
        tau = np.clip((t - self.starts[k]) / time, 0.0, 1.0)
        step = self.points[k + 1] - self.points[k]
        s = tau**3 * (10 - 15 * tau + 6 * tau**2)
        rate = 30 * tau**2 * (1 - tau) ** 2 / time
        change = 60 * tau * (1 - tau) * (1 - 2 * tau) / time**2
        return {"x": self.points[k] + s * step, "x_dot": rate * step, "x_ddot": change * step,
                "yaw": 0.0, "yaw_dot": 0.0}


if __name__ == "__main__":
    from quadnav.mission import MissionSettings, fly_mission
    from quadnav.world import load_world

    speed = float(sys.argv[1]) if len(sys.argv) > 1 else 1.5
    world = load_world("course:rotorpy/double_pillar")  # shipped with quadnav
    settings = MissionSettings(reference=f"{__file__}:StopAndGo(speed={speed})")
    metrics = fly_mission(world, (-1.1, -3, 1), (-1.1, 3, 1.5), settings=settings).metrics()
    print(f"stop and go at {speed:g} m/s: success {metrics['success']}, trajectory "
          f"{metrics['trajectory_duration_s']:.2f} s, margin kept "
          f"{metrics['trajectory_margin_m']:.3f} m by it and {metrics['flight_margin_m']:.3f} m "
          "by the flight")
