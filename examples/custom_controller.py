"""A controller of your own, in one file: the geometric SE(3) controller with an integral
of the position error (so a steady wind leaves no offset), registered by name and flown
through a course map in a wind by the same closed loop as the built-in controllers.

A controller is one compiled step ``step(memory, state (17,), reference (11,), gains,
vehicle, dt) -> motor commands (4,)`` (see :mod:`quadnav.control.contract`): ``memory`` is
its own array, slot 0 saying whether the commands were clipped. Use this file as a
template.

Run: python examples/custom_controller.py [MAP]   (a map with its own start and goal, such as
course:meam620/test_window, after quadnav maps fetch meam620/test_window; default: the
built-in forest)
"""

import sys

import numpy as np
from numba import njit

from quadnav.control import (
    SATURATED,
    Controller,
    SE3GainArrays,
    SE3Gains,
    register_controller,
    se3_gain_arrays,
    se3_step,
)
from quadnav.mission import MissionSettings, fly_mission
from quadnav.sim.settings import SimSettings
from quadnav.world import load_world

INTEGRAL = 1  # memory slots 1-3: the integral of the position error, m s


#: The gains: SE(3)'s, ki ((3,) 1/s^3) and the largest integral (m s). A plain tuple of
#: quadnav's types, not a class of this file: numba finds its compiled step in its cache
#: again only for argument types it can import again, and this file runs as __main__.
IntegralGains = tuple[SE3GainArrays, np.ndarray, float]


@njit(cache=True)
def se3_integral_step(memory, state, reference, g, v, dt):
    """SE(3) with the position reference moved by ki times the integrated error."""
    se3, ki, limit = g
    shifted = reference.copy()
    for a in range(3):
        error = reference[a] - state[a]
        memory[INTEGRAL + a] = min(max(memory[INTEGRAL + a] + error * dt, -limit), limit)
        shifted[a] += ki[a] / max(se3.kx[a], 1e-9) * memory[INTEGRAL + a]
    commands = se3_step(memory[SATURATED:SATURATED + 1], state, shifted, se3, v, dt)
    return commands


def se3_integral(vehicle, gains=None) -> Controller:
    """The factory ``--controller`` names call with the vehicle and the controller's own
    gains: here always SE(3)'s defaults and this integral's."""
    gains: IntegralGains = (se3_gain_arrays(SE3Gains()), np.array([4.0, 4.0, 8.0]), 0.5)
    return Controller("se3i", se3_integral_step, gains, 4)


register_controller("se3i", se3_integral)

if __name__ == "__main__":
    name = sys.argv[1] if len(sys.argv) > 1 else "forest"
    world = load_world(name)  # flown from its own start to its own goal
    wind = SimSettings(wind=(0.05, 0.0, 0.0))  # N: a steady breeze along x
    for controller in ("se3", "se3i"):
        mission = fly_mission(world, settings=MissionSettings(controller=controller, sim=wind))
        metrics = mission.metrics()
        print(f"{controller} in wind: success {metrics['success']}, RMS tracking error "
              f"{100 * metrics['rms_tracking_error_m']:.2f} cm, final error "
              f"{100 * metrics['final_error_m']:.2f} cm")
