"""Plain-Python winds in rotorpy's shape: ``update(t, position) -> wind velocity``, a
disturbance beside the steady force and the gusts, acting through the vehicle's drag on its
airspeed; rotorpy's own winds blow unchanged."""

from __future__ import annotations

import numpy as np
import pytest
from clitools import run_here

from quadnav.control.registry import make_controller
from quadnav.sim.settings import SimSettings
from quadnav.sim.simulate import simulate
from quadnav.sim.wind import WINDS, load_wind
from quadnav.trajectory.references.builtin import load_reference
from quadnav.vehicle.params import load_params

WINDS_FILE = '''
import numpy as np


class Steady:
    """A steady wind of ``velocity`` m/s."""

    def __init__(self, velocity=(1.0, 0.0, 0.0)):
        self.velocity = np.array(velocity, dtype=float)

    def update(self, t, position):
        return self.velocity


class Jet:
    """``speed`` m/s along x where y < ``edge`` m, still air elsewhere."""

    def __init__(self, speed=3.0, edge=0.0):
        self.speed, self.edge = speed, edge

    def update(self, t, position):
        return np.array([self.speed if position[1] < self.edge else 0.0, 0.0, 0.0])


class Random:
    """A new random wind every update, from numpy's global generator."""

    def update(self, t, position):
        return np.random.normal(0.0, 1.0, 3)


class Felt:
    """Hovers by motor speeds and keeps the wind it is told of."""

    def __init__(self, quad_params):
        self.speed = np.sqrt(quad_params["mass"] * 9.81 / 4 / quad_params["k_eta"])
        self.winds = []

    def update(self, t, state, flat_output):
        self.winds.append(state["wind"])
        return {"cmd_motor_speeds": np.full(4, self.speed)}
'''
#: A vehicle whose drag is the same along every body axis, so that a wind of velocity w
#: pushes it exactly as the force drag * w does.
EVEN = load_params("tello").replace(drag=np.array([0.05, 0.05, 0.05]))


@pytest.fixture
def winds(tmp_path):
    path = tmp_path / "my_winds.py"
    path.write_text(WINDS_FILE)
    return path


def test_a_steady_wind_pushes_an_even_drag_vehicle_as_the_force_drag_times_its_speed(winds):
    helix = load_reference("helix:radius=1,speed=1")
    blown = simulate(helix, EVEN, settings=SimSettings(
        wind_model=f"{winds}:Steady(velocity=[2.0, -1.0, 0.5])"))
    pushed = simulate(helix, EVEN, settings=SimSettings(wind=0.05 * np.array([2.0, -1.0, 0.5])))
    assert np.abs(blown.states - pushed.states).max() < 1e-9
    still = simulate(helix, EVEN)
    assert np.abs(blown.position - still.position).max() > 0.01


def test_the_wind_is_asked_at_the_vehicles_position_each_control_step(winds):
    """A jet that blows only where y < edge: a hover at y = 0 inside it is pushed off its
    point and pulled back; one outside it flies as in still air."""
    hover = load_reference("hover:duration=2")
    still = simulate(hover, EVEN)
    inside = simulate(hover, EVEN, settings=SimSettings(wind_model=f"{winds}:Jet(edge=1.0)"))
    outside = simulate(hover, EVEN, settings=SimSettings(wind_model=f"{winds}:Jet(edge=-1)"))
    assert inside.max_tracking_error > 0.01
    assert np.abs(outside.states - still.states).max() == 0.0


def test_a_controller_is_told_the_wind(winds):
    controller = make_controller(f"{winds}:Felt", EVEN)
    simulate(load_reference("hover:duration=1"), EVEN, controller=controller,
             settings=SimSettings(control_rate=100.0, settle_time=0.0,
                                  wind_model=f"{winds}:Steady(velocity=[0, 2, 0])"))
    felt = controller.python.controller.winds
    assert len(felt) == 101 and all(w.tolist() == [0.0, 2.0, 0.0] for w in felt)


def test_a_random_wind_flies_the_same_flight_from_the_same_seed(winds):
    hover = load_reference("hover:duration=1")

    def fly(seed: int) -> np.ndarray:
        settings = SimSettings(control_rate=200.0, seed=seed, wind_model=f"{winds}:Random")
        return simulate(hover, EVEN, settings=settings).states

    assert np.array_equal(fly(1), fly(1)) and not np.array_equal(fly(1), fly(2))


def test_rotorpys_own_wind_blows_a_course_map_flight(tmp_path):
    pytest.importorskip("rotorpy", reason="rotorpy (quadnav[test]) is not installed")
    wind = ("rotorpy.wind.default_winds:SinusoidWind(amplitudes=[1.5, 1.0, 0.0], "
            "frequencies=[0.5, 0.3, 0.0], phase=[0.0, 1.0, 0.0])")
    result = run_here("fly", "course:rotorpy/double_pillar", "--start", "0", "-4", "1",
                      "--goal", "0", "4", "1", "--wind", wind, "--control-rate", "250",
                      "--no-figures", "--quiet", "-o", tmp_path / "out")
    assert result.returncode == 0, result.stderr
    parameters = (tmp_path / "out" / "parameters.json").read_text()
    assert '"wind_model": "rotorpy.wind.default_winds:SinusoidWind(' in parameters


def test_a_registered_wind_is_known_by_its_name(winds):
    from quadnav.plugins import load_target

    WINDS.register("steady_test", load_target(f"{winds}:Steady"))
    try:
        wind = load_wind("steady_test(velocity=[0, 0, 1])")
    finally:
        WINDS.unregister("steady_test")
    assert wind.at(0.0, np.zeros(3)).tolist() == [0.0, 0.0, 1.0]
