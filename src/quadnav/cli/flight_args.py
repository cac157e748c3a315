"""Flags of the commands that fly: the trajectory's shape and timing, the vehicle, its
controller and the simulation. Kept apart from :mod:`quadnav.cli.args` so that commands
that only read maps or plan do not import the controllers, the simulator and the
trajectory stack."""

from __future__ import annotations

import argparse

from quadnav.cli.args import number_in
from quadnav.control.gains import course_gain_names
from quadnav.control.registry import DEFAULT_CONTROLLER, controller_class, controller_gains
from quadnav.errors import QuadnavError
from quadnav.limits import FORCE, GUSTS, RATE, SETTLE
from quadnav.sim.settings import SimSettings, default_record_rate
from quadnav.trajectory.generate import METHODS, TIMINGS
from quadnav.trajectory.references.builtin import DURATION
from quadnav.vehicle.params import (
    DEFAULT_PRESET,
    VehicleParams,
    load_params,
    vehicle_forms,
)


def _default(value: object, unset: bool) -> object:
    """A flag's default: ``value``, or None with ``unset`` (the command's mission fills it
    in, :mod:`quadnav.cli.mission_args`)."""
    return None if unset else value


def add_timing_arguments(parser: argparse.ArgumentParser, unset: bool = False) -> None:
    """--method and --timing: the trajectory's shape and how its segments are timed (with
    ``unset``, None when not given)."""
    parser.add_argument("--method", choices=METHODS.names(), default=_default("minsnap", unset),
                        help="shape of the trajectory: minimum snap, the course reports' "
                             "quintic or cubic, the minimum-jerk quintic-c2, or the quintic "
                             "with average-velocity ends and times length / speed "
                             "(default: minsnap)")
    parser.add_argument("--timing", choices=TIMINGS, default=_default("fastest", unset),
                        help="segment times: fastest cruises at --speed and slows only for "
                             "turns and the ends; rest-to-rest gives each segment a "
                             "stop-and-go move; snap-time trades snap for time (minsnap) "
                             "(default: fastest)")


def add_duration_argument(parser: argparse.ArgumentParser) -> None:
    """--duration S: how long a trajectory class of your own is flown."""
    parser.add_argument("--duration", type=number_in(DURATION), metavar="S",
                        help=f"how long a trajectory class of your own is flown, "
                             f"{DURATION.describe()} (default: as long as it says: its "
                             "duration, or the last of rotorpy's t_keyframes)")


def add_vehicle_arguments(parser: argparse.ArgumentParser, unset: bool = False) -> None:
    """--params NAME|FILE|SPEC (the vehicle; with ``unset``, None when not given) and
    --gains FILE (the controller)."""
    parser.add_argument("--params", default=_default(DEFAULT_PRESET, unset),
                        metavar="NAME|FILE|SPEC",
                        help=f"vehicle: {vehicle_forms()} (default: {DEFAULT_PRESET})")
    parser.add_argument("--gains", metavar="NAME|FILE",
                        help="the controller's gains: a TOML file of its keys, or a course "
                             f"gain table of the cascade ({', '.join(course_gain_names())}); "
                             "keys it leaves out keep the controller's gains tuned for the "
                             "vehicle")


def add_controller_argument(parser: argparse.ArgumentParser, unset: bool = False) -> None:
    """--controller NAME|SPEC (with ``unset``, None when not given)."""
    parser.add_argument("--controller", default=_default(DEFAULT_CONTROLLER, unset),
                        metavar="NAME|SPEC",
                        help="the controller: cascade (PX4-style), se3 (the geometric "
                             "controller of Lee et al., as in MEAM620 and rotorpy), another "
                             "registered name, or your own class in rotorpy's shape, "
                             "update(t, state, flat_output) -> commands, named where it is: "
                             "module:Class or path/to/file.py:Class, with keyword arguments "
                             "Class(key=value, ...); --gains tunes the cascade and se3, and "
                             "the cascade's inner loops that a class's attitude, rate and "
                             f"velocity commands fly through (default: {DEFAULT_CONTROLLER})")


def vehicle_and_gains(args: argparse.Namespace) -> tuple[VehicleParams, object]:
    """The vehicle and the controller's gains of :func:`add_vehicle_arguments` (files are
    read here); the controller of ``--controller`` is loaded and checked here (not built),
    so that a bad one is refused before any work."""
    controller = getattr(args, "controller", DEFAULT_CONTROLLER)
    controller_class(controller)
    vehicle = load_params(args.params)
    return vehicle, controller_gains(controller, vehicle, args.gains)


def add_simulation_arguments(parser: argparse.ArgumentParser, unset: bool = False) -> None:
    """--physics-rate, --control-rate, --wind FX FY FZ|SPEC, --gusts N and --settle S (with
    ``unset``, None when not given)."""
    parser.add_argument("--physics-rate", type=number_in(RATE),
                        default=_default(SimSettings.physics_rate, unset),
                        metavar="HZ", help=f"RK4 steps per second, {RATE.describe()} "
                                           f"(default: {SimSettings.physics_rate:g})")
    parser.add_argument("--control-rate", type=number_in(RATE),
                        default=_default(SimSettings.control_rate, unset),
                        metavar="HZ", help=f"controller updates per second, {RATE.describe()}; "
                                           "the physics rate must be a whole multiple "
                                           f"(default: {SimSettings.control_rate:g}); a "
                                           "plain-Python controller or wind runs once a "
                                           "control step: a lower rate costs less Python "
                                           "time")
    parser.add_argument("--wind", nargs="+", type=force_or_spec, metavar=("FX|SPEC", "FY FZ"),
                        help=f"steady wind as a force on the vehicle FX FY FZ, N, world "
                             f"frame, each {FORCE.describe()}; or a wind model, a class "
                             "with update(t, position) -> wind velocity m/s (world frame), "
                             "named module:Class or path/to/file.py:Class(key=value, ...): "
                             "the drag acts on the airspeed (default: none)")
    parser.add_argument("--gusts", type=number_in(GUSTS), default=_default(0.0, unset),
                        metavar="N",
                        help=f"random gusts: standard deviation of a force per axis, "
                             f"{GUSTS.describe()}, redrawn every "
                             f"{SimSettings.gust_period:g} s from the seed (default: 0)")
    parser.add_argument("--settle", type=number_in(SETTLE),
                        default=_default(SimSettings.settle_time, unset),
                        metavar="S", help=f"time flown after the reference ends, "
                                          f"{SETTLE.describe()} "
                                          f"(default: {SimSettings.settle_time:g})")


def add_strict_argument(parser: argparse.ArgumentParser) -> None:
    """--strict: a flight that kept less margin than asked fails (exit 1)."""
    parser.add_argument("--strict", action="store_true",
                        help="exit 1 when the flight kept less margin than asked off the legs, "
                             "by any amount (a warning line says so either way)")


def force_or_spec(text: str) -> float | str:
    """argparse type of ``--wind``'s values: a number (a force, N, in
    :data:`~quadnav.limits.FORCE`) or a wind model's spec."""
    try:
        float(text)
    except ValueError:
        return text
    return number_in(FORCE)(text)


def wind_arguments(values: list[float | str] | None) -> tuple[list[float], str | None]:
    """``--wind``'s values as the steady force (3,) N and the wind model's spec (or None).

    Raises:
        QuadnavError: neither three numbers nor one spec.
    """
    if values is None:
        return [0.0, 0.0, 0.0], None
    if len(values) == 3 and all(isinstance(value, float) for value in values):
        return [float(value) for value in values], None
    if len(values) == 1 and isinstance(values[0], str):
        return [0.0, 0.0, 0.0], values[0]
    raise QuadnavError(f"--wind: expected three forces FX FY FZ (N) or one wind model's spec, "
                       f"got {' '.join(f'{v:g}' if isinstance(v, float) else v for v in values)}")


def simulation_settings(args: argparse.Namespace) -> SimSettings:
    """The settings of :func:`add_simulation_arguments` and ``--seed``."""
    wind, wind_model = wind_arguments(args.wind)
    return SimSettings(physics_rate=args.physics_rate, control_rate=args.control_rate,
                       record_rate=default_record_rate(args.control_rate),
                       settle_time=args.settle, wind=wind, wind_model=wind_model,
                       gust_std=args.gusts, seed=args.seed)
