"""Controllers own their gains: a controller's factory takes the vehicle and its own gains,
a vehicle names the gain set each controller flies it with, ``--gains`` sets the gains of
whichever controller flies (SE(3)'s too), and the library never flies a vehicle with another
vehicle's gains."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from clitools import assert_user_error, run_here

from quadnav.config import as_plain
from quadnav.control.gains import CASCADE_SETS, Gains, gain_set
from quadnav.control.registry import (
    CONTROLLERS,
    controller_gains,
    gain_set_names,
    make_controller,
)
from quadnav.control.sampling import axis_loops
from quadnav.control.se3 import SE3Gains
from quadnav.errors import QuadnavError
from quadnav.mission import MissionSettings
from quadnav.sim.settings import SimSettings
from quadnav.sim.simulate import simulate
from quadnav.tracking import track_reference
from quadnav.trajectory.references.builtin import load_reference
from quadnav.vehicle.params import load_params

TELLO = load_params("tello")
RBE595 = load_params("rbe595")
#: The cascade's gain set shipped for the rbe595 vehicle, read as it is shipped.
RBE595_OWN = gain_set(Gains(), CASCADE_SETS, "rbe595")


def test_the_library_flies_a_vehicle_with_its_own_gains():
    # on main, MissionSettings(vehicle=rbe595) kept the Tello's gains, which the rbe595
    # vehicle (100 times the inertia) cannot fly well, where the command line loaded its own
    settings = MissionSettings(vehicle=RBE595)

    assert as_plain(settings.flown_gains) == as_plain(RBE595_OWN)
    assert as_plain(settings.flown_gains) != as_plain(Gains())
    assert as_plain(MissionSettings().flown_gains) == as_plain(Gains())  # the Tello's
    # another vehicle put in later flies its own too, not the gains of the one it replaced
    swapped = dataclasses.replace(MissionSettings(), vehicle=RBE595)
    assert as_plain(swapped.flown_gains) == as_plain(RBE595_OWN)
    # and so do the other entries of the library: a tracking and its parameters
    tracking = track_reference(load_reference("hover:duration=0.5"), RBE595)
    assert tracking.parameters()["gains"] == as_plain(RBE595_OWN)


def test_simulate_flies_the_vehicle_with_its_own_gains_when_given_none():
    # on main, simulate(reference, rbe595) with no gains and no controller flew the cascade's
    # defaults, the Tello's; it flies the gains tuned for the vehicle the controller knows
    step = load_reference("step:axis=x,size=0.5,duration=1.5")
    fast = SimSettings(control_rate=500.0, settle_time=0.0)
    own = simulate(step, RBE595, settings=fast)
    tuned = simulate(step, RBE595, controller_gains("cascade", RBE595), settings=fast)
    tellos = simulate(step, RBE595, Gains(), settings=fast)
    assert np.array_equal(own.states, tuned.states)
    assert not np.allclose(own.states, tellos.states, atol=1e-3)
    # a plant flown by a controller that knows another vehicle: that vehicle's gains
    known = simulate(step, TELLO, settings=fast, model=RBE595)
    assert np.array_equal(known.states, simulate(step, TELLO, controller_gains(
        "cascade", RBE595), settings=fast, model=RBE595).states)


def test_each_controller_builds_from_the_vehicle_and_its_own_gains():
    for name in CONTROLLERS.names():
        own = controller_gains(name, RBE595)
        assert make_controller(name, RBE595).gains.__class__ is make_controller(
            name, RBE595, own).gains.__class__
    assert isinstance(controller_gains("cascade", TELLO), Gains)
    assert isinstance(controller_gains("se3", TELLO), SE3Gains)
    assert "rbe595" in gain_set_names() and "tello" in gain_set_names()
    with pytest.raises(QuadnavError, match="expected gains of type SE3Gains, got Gains"):
        MissionSettings(controller="se3", gains=Gains())
    with pytest.raises(QuadnavError, match="names the gain set 'nope'"):
        MissionSettings(vehicle=TELLO.replace(gains="nope"))


def test_se3_gains_are_read_from_a_toml_file_over_the_vehicles_own(tmp_path):
    path = tmp_path / "se3.toml"
    path.write_text("kr = [300.0, 300.0, 80.0]\nkw = [30.0, 30.0, 16.0]\n")

    gains = controller_gains("se3", TELLO, path)

    assert gains.kr.tolist() == [300.0, 300.0, 80.0] and gains.kx.tolist() == [6.5, 6.5, 15.0]
    roll = axis_loops(make_controller("se3", TELLO, gains))[0]
    assert (roll.attitude, roll.rate_p) == (10.0, 30.0)  # kR / kw and kw, as flown
    path.write_text("kr = [300.0, 300.0]\n")
    with pytest.raises(QuadnavError, match=f"{path}: kr: expected a list of 3 numbers"):
        controller_gains("se3", TELLO, path)
    path.write_text("kx = [1e300, 1, 1]\n")  # flew, and diverged: exit 1, not bad input
    with pytest.raises(QuadnavError, match=rf"{path}: kx: expected each value from 0 to "
                                           r"10,000, got \[1e\+300, 1, 1\]"):
        controller_gains("se3", TELLO, path)
    with pytest.raises(QuadnavError, match="gain table p2a-starter: unknown key 'position'; "
                                           "expected one of kx, kv, kr, kw"):
        controller_gains("se3", TELLO, "p2a-starter")


def test_fly_and_track_take_gains_for_the_se3_controller(tmp_path):
    # on main: "--gains sets the cascade's gains; --controller se3 flies with its own"
    gains = tmp_path / "se3.toml"
    gains.write_text("kx = [5.0, 5.0, 12.0]\n")

    result = run_here("track", "hover:duration=1", "--controller", "se3", "--gains", gains,
                      "--no-figures", "-o", tmp_path / "hover")

    assert result.returncode == 0, result.stderr
    flown = json.loads((tmp_path / "hover" / "parameters.json").read_text())["gains"]
    assert flown == as_plain(SE3Gains(kx=np.array([5.0, 5.0, 12.0])))
    gains.write_text("[position]\nkp = [1.0, 1.0, 1.0]\n")
    assert_user_error(run_here("fly", "--controller", "se3", "--gains", gains,
                               "-o", tmp_path / "x"),
                      f"{gains}: unknown key 'position'; expected one of kx, kv, kr, kw")
    assert not (tmp_path / "x").exists()


#: A plain-Python controller commanding body rates (rotorpy's cmd_ctbr), which the cascade's
#: rate loop flies, and a compiled controller of one's own without a gain table.
MINE = '''
from quadnav.control.se3 import se3_controller


class Rates:
    control_abstraction = "cmd_ctbr"

    def __init__(self, quad_params):
        self.weight = quad_params["mass"] * 9.81

    def update(self, t, state, flat_output):
        return {"cmd_thrust": self.weight, "cmd_w": [0.0, 0.0, 0.0]}


def geometric(vehicle, gains=None):
    return se3_controller()
'''


def test_one_gains_rule_for_every_controller(tmp_path):
    """--gains sets the gains of whichever controller flies: the cascade's, SE(3)'s, and a
    plain-Python controller's inner loops' (the cascade's keys, tuned for the vehicle unless
    given); a compiled controller without a gain table refuses it."""
    (tmp_path / "mine.py").write_text(MINE)
    rates = f"{tmp_path / 'mine.py'}:Rates"
    # the inner loops fly the vehicle's own gains, in the library too (on main they flew
    # MissionSettings' default Gains(), the Tello's, whatever the vehicle)
    settings = MissionSettings(vehicle=RBE595, controller=rates)
    assert as_plain(settings.flown_gains) == as_plain(RBE595_OWN)
    def same(one, other) -> bool:  # compiled gains: tuples of arrays and numbers
        return all(np.array_equal(a, b) for a, b in zip(one.gains, other.gains, strict=True))

    flown = make_controller(rates, RBE595)
    assert same(flown, make_controller("cascade", RBE595))
    assert not same(flown, make_controller("cascade", TELLO))
    slow = tmp_path / "slow.toml"
    slow.write_text("[rate]\nkp = [15.0, 15.0, 15.0]\n")
    assert controller_gains(rates, RBE595, slow).rate.kp.tolist() == [15.0, 15.0, 15.0]
    with pytest.raises(QuadnavError, match="unknown key 'kx'; expected one of position"):
        controller_gains(rates, TELLO, {"kx": [1.0, 1.0, 1.0]})
    with pytest.raises(QuadnavError, match="expected gains of type Gains, got SE3Gains"):
        MissionSettings(controller=rates, gains=SE3Gains())  # refused before it flies
    # a compiled controller of one's own has none to set
    geometric = f"{tmp_path / 'mine.py'}:geometric"
    assert controller_gains(geometric, TELLO) is None
    assert_user_error(run_here("track", "hover", "--controller", geometric, "--gains", slow,
                               "-o", tmp_path / "x"),
                      f"controller {geometric}: it has no gain table to set (gains {slow} given)")
    assert not (tmp_path / "x").exists()
