"""quadnav's dynamics against the field's reference simulator, the real rotorpy package: the
same state gives the same derivative, and the same vehicle flying the same reference with
the same controller law and gains flies the same flight in quadnav's closed loop and in
rotorpy's simulator (its ``Environment``), with rotorpy's aerodynamics off and on.

The flights: rotorpy's ``SE3Control`` at rotorpy's own 100 Hz in its ``Environment`` (the
dynamics integrated by ``solve_ivp``, RK45 at its default tolerances, over each control
step), and quadnav's compiled SE(3) controller (the same law, given ``SE3Control``'s gains)
at 100 Hz in quadnav's loop (RK4 at 1 kHz), round a 2 m figure 8 in 5 s from a hover at
its start and 0.5 s of hover after it. They agree to within :data:`RMS_TOLERANCE` and
:data:`WORST_TOLERANCE` over the whole flight. Measured: the crazyflie's agree to 2e-10 m
RMS (4e-10 m at worst) with its aerodynamics off, and as closely with its rotor drag on,
which moves its flight by 4.7 cm RMS (7.7 cm at worst); the hummingbird's, with all four
of rotorpy's aerodynamic terms, to 0.007 mm RMS (0.013 mm at worst), what rotorpy's RK45
tolerances leave with its 5 ms motors (quadnav at 10 kHz flies the same). Each rotorpy
flight takes about a second.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from quadnav.control.se3 import SE3Gains, se3_controller
from quadnav.sim.flight import Flight
from quadnav.sim.settings import SimSettings
from quadnav.sim.simulate import simulate
from quadnav.trajectory.references.builtin import build_reference
from quadnav.trajectory.references.contract import Reference
from quadnav.vehicle.dynamics import STATE_SIZE, derivative, vehicle_arrays
from quadnav.vehicle.params import VehicleParams
from quadnav.vehicle.rotorpy_params import rotor_layout, vehicle_from_rotorpy

pytest.importorskip("rotorpy", reason="rotorpy (quadnav[test]) is not installed")
from rotorpy.controllers.quadrotor_control import SE3Control
from rotorpy.environments import Environment
from rotorpy.vehicles import crazyflie_params, hummingbird_params
from rotorpy.vehicles.multirotor import Multirotor

#: rotorpy's aerodynamic keys, and the crazyflie with them all 0 (rotorpy's aero=False).
AERODYNAMIC_KEYS = ("k_d", "k_z", "k_h", "k_flap", "c_Dx", "c_Dy", "c_Dz")
CRAZYFLIE = dict(crazyflie_params.quad_params)
CRAZYFLIE_WITHOUT_AERO = {**CRAZYFLIE, **dict.fromkeys(AERODYNAMIC_KEYS, 0.0)}
#: The hummingbird has parasitic drag, rotor drag and translational lift; no shipped vehicle
#: has a flapping moment, so it gets one (it moves the flight below by about 2 cm).
HUMMINGBIRD = {**hummingbird_params.quad_params, "k_flap": 1e-5}
#: The flights' rates (rotorpy's simulator and both controllers; quadnav's physics), Hz.
RATE, PHYSICS_RATE = 100.0, 1000.0
REFERENCE = "figure8:size=2,period=5"
SETTLE = 0.5
#: How far apart the two flights' positions may be, m: an engineering tolerance (a
#: millimetre, where the flights track the reference to centimetres), far above the
#: integrators' differences and far below what any of the modelled effects makes.
RMS_TOLERANCE, WORST_TOLERANCE = 1e-3, 2e-3


def rotorpy_state(state: np.ndarray, corners: list[int]) -> np.ndarray:
    """quadnav's state (17,) as rotorpy's vector (20,): quaternion (i, j, k, w), no wind,
    rotor speeds in rotorpy's order (``corners``: quadnav's rotor of each of rotorpy's)."""
    w, i, j, k = state[6:10]
    return np.concatenate([state[0:6], [i, j, k, w], state[10:13], np.zeros(3),
                           state[13:17][corners]])


@pytest.mark.parametrize("params", [CRAZYFLIE_WITHOUT_AERO, CRAZYFLIE, HUMMINGBIRD],
                         ids=["crazyflie-no-aero", "crazyflie", "hummingbird-all-aero"])
def test_the_state_derivative_is_rotorpys(params):
    """At random states, rotor speeds and commands, quadnav's derivative is rotorpy's
    ``Multirotor`` (aero on) to round-off: forces, torques, aerodynamics, motor lag."""
    vehicle = vehicle_from_rotorpy(params, "rotorpy")
    _, corners = rotor_layout(params, "rotorpy")
    arrays = vehicle_arrays(vehicle)
    multirotor = Multirotor(params, aero=True)
    rng = np.random.default_rng(7)
    for _ in range(50):
        state = np.zeros(STATE_SIZE)
        state[0:6] = rng.normal(0.0, 2.0, 6)
        quaternion = rng.normal(size=4)
        state[6:10] = quaternion / np.linalg.norm(quaternion)
        state[10:13] = rng.normal(0.0, 3.0, 3)
        state[13:17] = rng.uniform(0.3, 1.0, 4) * vehicle.rotor_speed_max
        command = rng.uniform(0.0, 1.0, 4) * vehicle.rotor_speed_max
        ours = np.empty(STATE_SIZE)
        derivative(state, command, arrays, np.zeros(3), np.zeros(3), ours)
        theirs = multirotor._s_dot_fn(0.0, rotorpy_state(state, corners), command[corners])
        np.testing.assert_allclose(rotorpy_state(ours, corners), theirs, rtol=1e-9,
                                   atol=1e-9 * np.max(np.abs(theirs)))


class FlatOutputs:
    """A quadnav reference as a rotorpy trajectory, ``update(t) -> flat outputs`` (jerk and
    snap 0: ``SE3Control`` does not read them; the yaw is 0)."""

    def __init__(self, reference: Reference) -> None:
        self.reference = reference

    def update(self, t: float) -> dict:
        r = self.reference
        return {"x": r.position(t), "x_dot": r.velocity(t), "x_ddot": r.acceleration(t),
                "x_dddot": np.zeros(3), "x_ddddot": np.zeros(3), "yaw": 0.0, "yaw_dot": 0.0}


def quadnav_flight(vehicle: VehicleParams, control: SE3Control, reference: Reference) -> Flight:
    """``vehicle`` flown round ``reference`` in quadnav's loop by its SE(3) controller with
    the gains of rotorpy's ``control``, recorded at every control step."""
    gains = SE3Gains(kx=control.kp_pos, kv=control.kd_pos, kr=[control.kp_att] * 3,
                     kw=[control.kd_att] * 3)
    settings = SimSettings(control_rate=RATE, physics_rate=PHYSICS_RATE, record_rate=RATE,
                           settle_time=SETTLE)
    return simulate(reference, vehicle, settings=settings, controller=se3_controller(gains))


def rotorpy_flight(params: dict, aero: bool, reference: Reference, vehicle: VehicleParams,
                   duration: float) -> np.ndarray:
    """Positions (N, 3) every 1 / RATE s of rotorpy's simulator flying ``params`` round
    ``reference`` for ``duration`` s from the hover at its start, by ``SE3Control``."""
    start = {"x": reference.position(0.0), "v": np.zeros(3), "q": np.array([0, 0, 0, 1.0]),
             "w": np.zeros(3), "wind": np.zeros(3),
             "rotor_speeds": np.full(4, vehicle.hover_rotor_speed)}
    environment = Environment(Multirotor(params, start, aero=aero), SE3Control(params),
                              FlatOutputs(reference), sim_rate=RATE)
    return environment.run(t_final=duration)["state"]["x"]


CASES = {"crazyflie-no-aero": (CRAZYFLIE_WITHOUT_AERO, False),
         "crazyflie": (CRAZYFLIE, True), "hummingbird-all-aero": (HUMMINGBIRD, True)}


@functools.cache
def flights(case: str) -> tuple[Flight, np.ndarray]:
    """quadnav's flight and rotorpy's positions for one of :data:`CASES`, flown once."""
    params, aero = CASES[case]
    reference = build_reference(REFERENCE)
    vehicle = vehicle_from_rotorpy(params, case)
    ours = quadnav_flight(vehicle, SE3Control(params), reference)
    return ours, rotorpy_flight(params, aero, reference, vehicle, float(ours.t[-1]))


def distances(ours: np.ndarray, theirs: np.ndarray) -> np.ndarray:
    """How far apart (N,) m two flights' positions (at the same times from 0) are."""
    count = min(len(ours), len(theirs))
    return np.linalg.norm(ours[:count] - theirs[:count], axis=1)


@pytest.mark.parametrize("case", list(CASES))
def test_a_flight_agrees_with_rotorpys_simulator(case):
    ours, theirs = flights(case)
    apart = distances(ours.position, theirs)
    assert len(apart) > 0.99 * ours.t[-1] * RATE  # the whole flight, sample by sample
    # a real flight, well within the rotors' range (where both mixers are exact)
    assert ours.ending.name == "COMPLETED" and 0.02 < ours.rms_tracking_error < 0.5
    assert ours.commands.min() > 0.02 and ours.commands.max() < 0.98
    assert np.sqrt(np.mean(apart ** 2)) < RMS_TOLERANCE and apart.max() < WORST_TOLERANCE


def test_the_agreement_tells_the_rotor_drag_apart():
    """The tolerance is tight enough to see the crazyflie's rotor drag: quadnav's flight
    without it is more than ten times the tolerance from rotorpy's flight with it."""
    without = vehicle_from_rotorpy(CRAZYFLIE_WITHOUT_AERO, "crazyflie")
    ours = quadnav_flight(without, SE3Control(CRAZYFLIE), build_reference(REFERENCE))
    apart = distances(ours.position, flights("crazyflie")[1])
    assert np.sqrt(np.mean(apart ** 2)) > 10 * RMS_TOLERANCE
