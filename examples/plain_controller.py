"""A plain-Python controller in rotorpy's shape, in one file: a PD law on the position error
that commands the collective thrust and the attitude (rotorpy's ``cmd_ctatt``), which
quadnav's own attitude and body-rate loops fly.

A controller is a class built with the vehicle's parameter dict (rotorpy's keys: ``mass``,
``Ixx``, ``k_eta``, ``rotor_pos``, ...) and keyword arguments of its own, with
``update(t, state, flat_output) -> dict`` (rotorpy's ``controller_template.py``): ``state``
holds ``x``, ``v``, ``q`` (i, j, k, w), ``w``, ``wind``, ``rotor_speeds``; ``flat_output``
holds ``x``, ``x_dot``, ``x_ddot``, ``x_dddot``, ``x_ddddot``, ``yaw``, ``yaw_dot``. Return
``cmd_motor_speeds`` (rad/s), ``cmd_motor_thrusts`` (N), ``cmd_thrust`` (N) with
``cmd_moment`` (N m), ``cmd_q`` or ``cmd_w`` (rad/s), or ``cmd_v`` (m/s). Use this file as a
template; the command line flies it too::

    quadnav fly --controller "examples/plain_controller.py:PDAttitude(kp=6.5, kd=4.0)" \
        --control-rate 250

Python runs at every control step, so it flies at 250 Hz, a quarter of the default 1 kHz's
calls (the physics stays at 1 kHz; the control rate is checked against the attitude and rate
loops that fly its commands).

Run: python examples/plain_controller.py [MAP]   (a map with its own start and goal;
default: the built-in forest)
"""

import sys

import numpy as np
from scipy.spatial.transform import Rotation

from quadnav.mission import MissionSettings, fly_mission
from quadnav.sim.settings import SimSettings
from quadnav.world import load_world

GRAVITY = np.array([0.0, 0.0, 9.81])  # m/s^2, what the thrust holds up


class PDAttitude:
    """Thrust and attitude from a PD law on the position error, gains in 1/s^2 and 1/s,
    plus the drag of the four rotors (rotorpy's ``k_d``, ``k_z``) at the hover speed."""

    # what update returns (else found from its first call); declared, the control rate is
    # checked against the attitude and rate loops that fly it before the flight
    control_abstraction = "cmd_ctatt"

    def __init__(self, quad_params, kp=6.5, kd=4.0):
        self.mass, self.kp, self.kd = quad_params["mass"], kp, kd
        hover = np.sqrt(self.mass * GRAVITY[2] / 4 / quad_params["k_eta"])  # rad/s
        self.drag = 4 * hover * np.array([quad_params["k_d"]] * 2 + [quad_params["k_z"]])

    def update(self, t, state, flat_output):
        acceleration = (flat_output["x_ddot"] + self.kp * (flat_output["x"] - state["x"])
                        + self.kd * (flat_output["x_dot"] - state["v"]))
        force = self.mass * (acceleration + GRAVITY) + self.drag * flat_output["x_dot"]
        z = force / np.linalg.norm(force)  # body z along the force, heading the yaw
        yaw = flat_output["yaw"]
        y = np.cross(z, [np.cos(yaw), np.sin(yaw), 0.0])
        y /= np.linalg.norm(y)
        attitude = Rotation.from_matrix(np.column_stack([np.cross(y, z), y, z]))
        body_z = Rotation.from_quat(state["q"]).apply([0.0, 0.0, 1.0])
        return {"cmd_thrust": force @ body_z, "cmd_q": attitude.as_quat()}


if __name__ == "__main__":
    name = sys.argv[1] if len(sys.argv) > 1 else "forest"
    settings = MissionSettings(controller=f"{__file__}:PDAttitude(kp=6.5, kd=4.0)",
                               sim=SimSettings(control_rate=250.0))
    mission = fly_mission(load_world(name), settings=settings)  # its own start and goal
    flight = mission.flight
    print(f"PD attitude in {name}: success {mission.success}, RMS tracking error "
          f"{100 * flight.rms_tracking_error:.2f} cm, {flight.duration:.1f} s flown in "
          f"{flight.wall_time:.1f} s")
