"""Flags of the commands that fly: the trajectory's shape and timing, the vehicle, its
controller and the simulation. Kept apart from :mod:`quadnav.cli.args` so that commands
that only read maps or plan do not import the controllers, the simulator and the
trajectory stack."""

from __future__ import annotations

import argparse

from quadnav.cli.args import number_in
from quadnav.control.gains import Gains, course_gain_names, load_gains
from quadnav.control.registry import CONTROLLERS, DEFAULT_CONTROLLER
from quadnav.errors import QuadnavError
from quadnav.limits import FORCE, GUSTS, RATE, SETTLE
from quadnav.sim.settings import SimSettings, default_record_rate
from quadnav.trajectory.generate import METHODS, TIMINGS
from quadnav.trajectory.references import DURATION
from quadnav.vehicle.params import (
    DEFAULT_PRESET,
    VehicleParams,
    load_params,
    vehicle_forms,
)


def add_timing_arguments(parser: argparse.ArgumentParser) -> None:
    """--method and --timing: the trajectory's shape and how its segments are timed."""
    parser.add_argument("--method", choices=METHODS.names(), default="minsnap",
                        help="shape of the trajectory: minimum snap, the course reports' "
                             "quintic or cubic, the minimum-jerk quintic-c2, or the quintic "
                             "with average-velocity ends and times length / speed "
                             "(default: minsnap)")
    parser.add_argument("--timing", choices=TIMINGS, default="fastest",
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


def add_vehicle_arguments(parser: argparse.ArgumentParser) -> None:
    """--params NAME|FILE (the vehicle) and --gains FILE (the controller)."""
    parser.add_argument("--params", default=DEFAULT_PRESET, metavar="NAME|FILE",
                        help=f"vehicle: {vehicle_forms()} (default: {DEFAULT_PRESET})")
    parser.add_argument("--gains", metavar="NAME|FILE",
                        help="controller gains: a TOML file, or a course gain table ("
                             f"{', '.join(course_gain_names())}); keys it leaves out keep "
                             "the gains tuned for the vehicle")


def add_controller_argument(parser: argparse.ArgumentParser) -> None:
    """--controller NAME."""
    parser.add_argument("--controller", choices=CONTROLLERS.names(), default=DEFAULT_CONTROLLER,
                        help="the controller: cascade (PX4-style, tuned by --gains) or se3 "
                             "(the geometric controller of Lee et al., rotorpy's gains) "
                             f"(default: {DEFAULT_CONTROLLER})")


def vehicle_and_gains(args: argparse.Namespace) -> tuple[VehicleParams, Gains]:
    """The vehicle and the gains of :func:`add_vehicle_arguments` (files are read here)."""
    controller = getattr(args, "controller", DEFAULT_CONTROLLER)
    if args.gains is not None and controller != DEFAULT_CONTROLLER:
        raise QuadnavError(f"--gains sets the cascade's gains; --controller {controller} "
                           "flies with its own")
    vehicle = load_params(args.params)
    return vehicle, load_gains(args.gains, vehicle.gains)


def add_simulation_arguments(parser: argparse.ArgumentParser) -> None:
    """--physics-rate, --control-rate, --wind FX FY FZ, --gusts N and --settle S."""
    parser.add_argument("--physics-rate", type=number_in(RATE), default=SimSettings.physics_rate,
                        metavar="HZ", help=f"RK4 steps per second, {RATE.describe()} "
                                           f"(default: {SimSettings.physics_rate:g})")
    parser.add_argument("--control-rate", type=number_in(RATE), default=SimSettings.control_rate,
                        metavar="HZ", help=f"controller updates per second, {RATE.describe()}; "
                                           "the physics rate must be a whole multiple "
                                           f"(default: {SimSettings.control_rate:g})")
    parser.add_argument("--wind", nargs=3, type=number_in(FORCE), default=[0.0, 0.0, 0.0],
                        metavar=("FX", "FY", "FZ"),
                        help=f"steady wind as a force on the vehicle, world frame, each "
                             f"{FORCE.describe()} (default: none)")
    parser.add_argument("--gusts", type=number_in(GUSTS), default=0.0, metavar="N",
                        help=f"random gusts: standard deviation of a force per axis, "
                             f"{GUSTS.describe()}, redrawn every "
                             f"{SimSettings.gust_period:g} s from the seed (default: 0)")
    parser.add_argument("--settle", type=number_in(SETTLE), default=SimSettings.settle_time,
                        metavar="S", help=f"time flown after the reference ends, "
                                          f"{SETTLE.describe()} "
                                          f"(default: {SimSettings.settle_time:g})")


def add_strict_argument(parser: argparse.ArgumentParser) -> None:
    """--strict: a flight that kept less margin than asked fails (exit 1)."""
    parser.add_argument("--strict", action="store_true",
                        help="exit 1 when the flight kept less margin than asked off the legs, "
                             "by any amount (a warning line says so either way)")


def simulation_settings(args: argparse.Namespace) -> SimSettings:
    """The settings of :func:`add_simulation_arguments` and ``--seed``."""
    return SimSettings(physics_rate=args.physics_rate, control_rate=args.control_rate,
                       record_rate=default_record_rate(args.control_rate),
                       settle_time=args.settle, wind=args.wind, gust_std=args.gusts,
                       seed=args.seed)
