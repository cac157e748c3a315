"""Every number has a stated range, checked before any work: flags, map values, settings,
and the products (samples, simulation steps) that would otherwise allocate without bound."""

from __future__ import annotations

import argparse
import math

import numpy as np
import pytest

from quadnav.cli.args import number_in
from quadnav.errors import QuadnavError
from quadnav.limits import (
    MAX_CONTROL_STEPS,
    PLAN_TIME,
    SEED,
    SPEED,
    check_count,
)
from quadnav.planning import PlannerSettings
from quadnav.sim.settings import SimSettings
from quadnav.sim.simulate import flight_steps, simulate
from quadnav.trajectory.model import hold_trajectory
from quadnav.world import World


def test_a_range_says_what_it_accepts():
    assert SPEED.describe() == "from 0.01 to 100 m/s"
    assert PLAN_TIME.describe() == "above 0, at most 3,600 s"
    assert SEED.describe() == "a whole number from 0 to 9,223,372,036,854,775,807"
    assert 0.01 in SPEED and 100 in SPEED and 0.0099 not in SPEED and 101 not in SPEED
    assert 0 not in PLAN_TIME and 1e-9 in PLAN_TIME
    for bad in (math.nan, math.inf, -math.inf, "1", None, True):
        assert bad not in SPEED
    assert 2**63 - 1 in SEED and 2**63 not in SEED and 1.5 not in SEED
    with pytest.raises(QuadnavError, match=r"^speed: expected from 0\.01 to 100 m/s, got "
                                           r"1,000,000,000$"):
        SPEED.check(1e9, "speed")


def test_number_types_name_the_range_and_refuse_what_is_not_a_number():
    speed = number_in(SPEED)
    assert speed("2.5") == 2.5
    for text in ("0", "1e9", "nan", "inf", "abc", "", "9" * 5000):
        with pytest.raises(argparse.ArgumentTypeError, match=r"expected from 0\.01 to 100 m/s"):
            speed(text)
    seed = number_in(SEED)
    assert seed("12") == 12
    for text in ("1.5", "-1", str(2**63), "9" * 5000):
        with pytest.raises(argparse.ArgumentTypeError, match="expected a whole number from 0"):
            seed(text)


def test_counts_over_their_bound_say_which_flags_lower_them():
    check_count(1000, 1000, "x", "y")
    with pytest.raises(QuadnavError, match=r"^a flight gives steps: 3,000,001, at most "
                                           r"1,000; lower --rate$"):
        check_count(3_000_000.5, 1000, "a flight gives steps", "lower --rate")
    with pytest.raises(QuadnavError, match="too many, at most 1,000"):
        check_count(math.inf, 1000, "a flight gives steps", "lower --rate")


def test_a_flight_too_long_for_its_rates_is_refused_before_anything_is_allocated():
    settings = SimSettings()
    seconds = MAX_CONTROL_STEPS / settings.control_rate
    assert flight_steps(seconds - settings.settle_time - 1.0, settings) <= MAX_CONTROL_STEPS
    with pytest.raises(QuadnavError, match=r"control steps: 2,5.*lower --control-rate or "
                                           r"--settle, or fly faster \(--speed\)"):
        simulate(hold_trajectory([0.0, 0.0, 1.0], 2500.0), settings=settings)
    with pytest.raises(QuadnavError, match=r"physics steps: 20,001,000, at most 20,000,000; "
                                           r"lower --physics-rate"):
        flight_steps(198.0, SimSettings(physics_rate=100_000, control_rate=100))
    with pytest.raises(QuadnavError, match="lasts 4000 s, longer than the 3600 s a "
                                           r"trajectory may last: fly faster \(--speed\)"):
        flight_steps(4000.0, settings)


def test_sampling_a_trajectory_is_bounded():
    assert len(hold_trajectory([0.0, 0.0, 1.0], 10.0).sample(1e-4).t) == 100_001
    with pytest.raises(QuadnavError, match=r"a 100 s reference sampled every 0.0001 s gives "
                                           r"samples: 1,000,001, at most 1,000,000; sample less "
                                           r"often \(--dt\)"):
        hold_trajectory([0.0, 0.0, 1.0], 100.0).sample(1e-4)


@pytest.mark.parametrize(("changes", "message"), [
    ({"time_limit": 1e9}, "time limit: expected above 0, at most 3,600 s, got 1,000,000,000"),
    ({"max_iterations": 10**12}, "max iterations: expected a whole number from 1 to 5,000,000"),
    ({"step": 1e-9}, "step: expected from 0.001 to 10,000 m"),
    ({"seed": -1}, "seed: expected a whole number from 0"),
])
def test_planner_settings_have_ranges(changes, message):
    with pytest.raises(QuadnavError, match=message):
        PlannerSettings(**changes)


@pytest.mark.parametrize(("boundary", "message"), [
    ([-1e154, 0, 0, 1e154, 1, 1], "boundary must be from -1e\\+07 to 1e\\+07"),
    ([0, 0, 0, 1e-200, 1e-200, 1e-200], "a box of size 1e-200 x 1e-200 x 1e-200 m has no volume"),
    ([0, 0, 0, 1, 1, np.inf], "boundary must be finite"),
])
def test_worlds_made_in_python_are_checked_too(boundary, message):
    with pytest.raises(QuadnavError, match=message):
        World(boundary=boundary)
    with pytest.raises(QuadnavError, match="colors must be from 0 to 1"):
        World(boundary=[0, 0, 0, 1, 1, 1], blocks=[[0, 0, 0, 1, 1, 1]], colors=[[0, 0, 255]])
    with pytest.raises(QuadnavError, match="margin: expected from 0 to 100 m, got 1,000"):
        World(boundary=[0, 0, 0, 1, 1, 1], margin=1000.0)
