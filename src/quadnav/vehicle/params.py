"""The quadrotor's physical parameters: :class:`VehicleParams`, presets and TOML files.

Rotor model: rotor ``i`` spinning at ``w_i`` rad/s pushes ``k_f w_i^2`` N along the body
z axis and twists the body about z by ``-s_i k_m w_i^2`` N m, where ``s_i`` is +1 for a
rotor spinning counter-clockwise seen from above. A motor command ``u`` in [0, 1] asks
for ``u`` times the rotor's largest thrust (as the RBE595 starter's ``U``): the rotor
speed chases ``w_max sqrt(u)`` with a first-order lag.

Drag: a linear drag on the body-frame airspeed (``drag``), and rotorpy's aerodynamics
(all zero in the presets): the rotor drag (H force) each rotor meets at its hub,
quadratic parasitic drag on the frame, translational lift and the flapping moment, as
rotorpy's ``Multirotor`` computes them (see :mod:`quadnav.vehicle.dynamics`).

Presets are TOML files shipped in ``quadnav/vehicle/presets`` (``tello``, ``rbe595``);
each states its sources; a plug-in adds one to :data:`PRESETS`. A user's file sets any keys
on top of the preset named by its ``based_on`` key (default ``tello``). A rotorpy parameter
dict is a vehicle too (:mod:`quadnav.vehicle.rotorpy_params`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.config import from_table, read_toml, require, vector_field
from quadnav.errors import QuadnavError
from quadnav.inputfiles import not_a_file, special_file
from quadnav.plugins import Registry, load_target, parse_spec

#: Standard gravity, m/s^2.
GRAVITY = 9.81
#: The preset used when none is named.
DEFAULT_PRESET = "tello"



@dataclass(frozen=True, eq=False)
class VehicleParams:
    """A quadrotor in the X configuration.

    Attributes:
        name: preset or file name, for reports.
        mass: kg.
        inertia: (3,) principal moments of inertia about body x, y, z, kg m^2.
        arm_length: distance from the centre of mass to each rotor axis, m.
        thrust_coefficient: ``k_f``, N / (rad/s)^2.
        torque_coefficient: ``k_m``, N m / (rad/s)^2.
        rotor_speed_max: largest rotor speed, rad/s.
        motor_time_constant: first-order lag of the rotor speed, s.
        drag: (3,) linear drag coefficients along body x, y, z, N / (m/s).
        rotor_drag: (3,) rotor drag coefficients along body x, y, z, N / (rad/s) / (m/s)
            (rotorpy's ``k_d, k_d, k_z``): rotor ``i`` spinning at ``w_i`` meets
            ``-w_i diag(rotor_drag) u_i`` at its hub, ``u_i`` the airspeed there in body
            axes (the body's airspeed plus the body rates' share, ``w x r_i``).
        parasitic_drag: (3,) quadratic drag coefficients along body x, y, z, N / (m/s)^2
            (rotorpy's ``c_Dx, c_Dy, c_Dz``): ``-|u| diag(parasitic_drag) u`` at the
            centre, ``u`` the body-frame airspeed.
        translational_lift: N / (m/s)^2 (rotorpy's ``k_h``): each rotor's thrust grows by
            ``translational_lift (u_x^2 + u_y^2)``, ``u`` the airspeed at its hub.
        flapping: N m / (rad/s) / (m/s) (rotorpy's ``k_flap``): each rotor twists the body
            by ``-flapping w_i (u_i x e_z)``, the blade flapping moment.
        body_size: (3,) size of the collision box along body x, y, z, m.
        gravity: m/s^2.
        gains: name of the controller gain set tuned for this vehicle (see
            :func:`quadnav.control.registry.gain_set_names`).
    """

    name: str = "custom"
    mass: float = 0.08
    inertia: FloatArray = vector_field(9.0e-5, 9.0e-5, 1.7e-4)
    arm_length: float = 0.06
    thrust_coefficient: float = 1.8e-7
    torque_coefficient: float = 1.03e-9
    rotor_speed_max: float = 1490.0
    motor_time_constant: float = 0.02
    drag: FloatArray = vector_field(0.04, 0.04, 0.06)
    rotor_drag: FloatArray = vector_field(0.0, 0.0, 0.0)
    parasitic_drag: FloatArray = vector_field(0.0, 0.0, 0.0)
    translational_lift: float = 0.0
    flapping: float = 0.0
    body_size: FloatArray = vector_field(0.10, 0.10, 0.05)
    gravity: float = GRAVITY
    gains: str = "tello"

    def __post_init__(self) -> None:
        positive = ("mass", "arm_length", "thrust_coefficient", "torque_coefficient",
                    "rotor_speed_max", "motor_time_constant", "gravity")
        require([(math.isfinite(getattr(self, key)) and getattr(self, key) > 0,
                  f"{key} must be > 0, got {getattr(self, key)}") for key in positive] + [
            (bool(np.all(self.inertia > 0)), f"inertia must be > 0, got {self.inertia}"),
            (bool(np.all(self.drag >= 0)), f"drag must be >= 0, got {self.drag}"),
            *[(bool(np.all(np.isfinite(getattr(self, key)) & (getattr(self, key) >= 0))),
               f"{key} must be >= 0, got {getattr(self, key)}")
              for key in ("rotor_drag", "parasitic_drag", "translational_lift", "flapping")],
            (bool(np.all(self.body_size > 0)), f"body_size must be > 0, got {self.body_size}"),
            (self.max_total_thrust > self.weight,
             f"the rotors lift {self.max_total_thrust:.3g} N in all, not more than the "
             f"weight {self.weight:.3g} N"),
        ])

    def replace(self, **changes: object) -> VehicleParams:
        """A copy with some fields changed (see :func:`dataclasses.replace`)."""
        return dataclasses.replace(self, **changes)

    def half_extents(self, yaw: float = 0.0) -> FloatArray:
        """How far (3,), m, the level body box reaches from its centre along the world's
        x, y and z axes when it heads ``yaw`` rad: ``body_size / 2`` at yaw 0."""
        c, s = abs(math.cos(yaw)), abs(math.sin(yaw))
        x, y, z = 0.5 * self.body_size
        return np.array([c * x + s * y, s * x + c * y, z])

    def half_extents_any_heading(self) -> FloatArray:
        """How far (3,), m, the level body box can reach from its centre along the world's x,
        y and z axes whatever its heading: the half diagonal of its footprint along x and y
        (the most :meth:`half_extents` gives over every yaw)."""
        x, y, z = 0.5 * self.body_size
        return np.array([math.hypot(x, y), math.hypot(x, y), z])

    @property
    def weight(self) -> float:
        """m g, N."""
        return self.mass * self.gravity

    @property
    def max_rotor_thrust(self) -> float:
        """Thrust of one rotor at full speed, N."""
        return self.thrust_coefficient * self.rotor_speed_max ** 2

    @property
    def max_total_thrust(self) -> float:
        """Thrust of all four rotors at full speed, N."""
        return 4.0 * self.max_rotor_thrust

    @property
    def torque_per_thrust(self) -> float:
        """``k_m / k_f``: yaw torque per newton of rotor thrust, m."""
        return self.torque_coefficient / self.thrust_coefficient

    @property
    def hover_command(self) -> float:
        """Motor command in [0, 1] that hovers: a quarter of the weight per rotor."""
        return self.weight / self.max_total_thrust

    @property
    def hover_rotor_speed(self) -> float:
        """Each rotor's speed in a hover, rad/s."""
        return self.rotor_speed_max * math.sqrt(self.hover_command)

    @property
    def hover_drag(self) -> FloatArray:
        """(3,) the linear drag, N / (m/s), along body x, y, z, that the vehicle meets
        flying slowly with its rotors near the hover speed: ``drag`` plus the rotor drag of
        the four rotors there, ``4 w_hover rotor_drag`` (the quadratic parasitic drag
        vanishes at low speed). What quadnav's linear models of the vehicle (the
        trajectory's envelope) count."""
        return self.drag + 4.0 * self.hover_rotor_speed * self.rotor_drag


#: Where the shipped presets are.
_PRESETS = resources.files("quadnav.vehicle") / "presets"


def shipped_preset(name: str) -> VehicleParams:
    """The preset ``name`` shipped as ``quadnav/vehicle/presets/NAME.toml``."""
    with resources.as_file(_PRESETS / f"{name}.toml") as real:
        table = read_toml(real)
    table.pop("based_on", None)
    return from_table(VehicleParams(name=name), table, f"preset {name}")


#: ``preset() -> VehicleParams``: a new one on every call.
Preset = Callable[[], VehicleParams]
#: Vehicle presets by name: those shipped, those of installed packages'
#: ``quadnav.vehicles`` entry points, those registered (``PRESETS.register(name, preset)``).
PRESETS: Registry[Preset] = Registry("vehicle preset", "quadnav.vehicles", {
    name: functools.partial(shipped_preset, name)
    for name in sorted(p.name.removesuffix(".toml") for p in _PRESETS.iterdir()
                       if p.name.endswith(".toml"))
})


def preset_names() -> list[str]:
    """Names of the presets: those shipped, then those of plug-ins."""
    return PRESETS.names()


def vehicle_forms() -> str:
    """What names a vehicle (:func:`load_params`), for help texts and messages."""
    return (f"a vehicle preset ({', '.join(preset_names())}), a TOML file or a rotorpy "
            "parameter dict (module:NAME or path/to/file.py:NAME)")


def load_params(spec: str | Path = DEFAULT_PRESET) -> VehicleParams:
    """A preset by name (see :func:`preset_names`), a TOML file's parameters, or a rotorpy
    parameter dict named where it is, ``module:NAME`` or ``path/to/file.py:NAME``, with
    keys replaced by keyword arguments if any (``...:quad_params(k_d=0, k_z=0)``; see
    :mod:`quadnav.vehicle.rotorpy_params`)."""
    if str(spec) in PRESETS:
        return PRESETS.get(str(spec))()
    path = Path(spec)
    if path.is_file():
        return params_from_table(read_toml(path), str(path), path.stem)
    kind = special_file(path)
    if kind is not None:
        raise QuadnavError(f"{spec}: {not_a_file(kind, 'a vehicle TOML file')}")
    if ":" in str(spec):
        return _rotorpy_vehicle(str(spec))
    if path.suffix or len(path.parts) > 1:
        raise QuadnavError(f"{spec}: no such file: expected {vehicle_forms()}")
    raise QuadnavError(f"{spec}: expected {vehicle_forms()}")


def params_from_table(table: dict, where: str, name: str = "custom") -> VehicleParams:
    """The vehicle a vehicle file's keys ``table`` describe: set on top of the preset its
    ``based_on`` names (default ``tello``), called ``name`` unless the table names it;
    ``where`` names the table in messages."""
    table = dict(table)
    base = table.pop("based_on", DEFAULT_PRESET)
    if base not in preset_names():
        raise QuadnavError(f"{where}: based_on must name a preset "
                           f"({', '.join(preset_names())}), got {base!r}")
    return from_table(load_params(base).replace(name=name), table, where)


def _rotorpy_vehicle(text: str) -> VehicleParams:
    """The vehicle of the rotorpy dict that ``text`` names (see :func:`load_params`), called
    after its module or file (and the dict's name, unless it is ``quad_params``)."""
    # imported here: the conversion module builds on this one
    from quadnav.vehicle.rotorpy_params import ROTORPY_KEYS, vehicle_from_rotorpy

    spec = parse_spec(text, "vehicle")
    table = load_target(spec.target, "vehicle")
    if not isinstance(table, Mapping):
        raise QuadnavError(f"vehicle {spec.target}: expected a rotorpy parameter dict, got "
                           f"{type(table).__name__}")
    unknown = sorted(set(spec.kwargs) - ROTORPY_KEYS - set(table))
    if unknown:
        raise QuadnavError(f"vehicle {text}: unknown key {unknown[0]!r}; expected one of "
                           f"{', '.join(sorted(ROTORPY_KEYS | set(table)))}")
    where, _, attribute = spec.target.partition(":")
    name = Path(where).stem if where.endswith(".py") else where.rpartition(".")[2]
    if attribute != "quad_params":
        name += f".{attribute}"
    return vehicle_from_rotorpy({**table, **spec.kwargs}, name, f"vehicle {text}")
