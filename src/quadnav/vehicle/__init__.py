"""The simulated quadrotor: parameters (:mod:`.params`), rotor layout and mixer
(:mod:`.rotors`), 6-DOF dynamics (:mod:`.dynamics`) and quaternions (:mod:`.quaternion`).

What a plug-in needs is here: :class:`VehicleParams` and :func:`load_params` (a preset, a
TOML file or a rotorpy dict), :data:`PRESETS` to name a vehicle of one's own, and what a
compiled controller is given, :func:`vehicle_arrays` (:class:`VehicleArrays`) and the
state's slices (:data:`POSITION`, :data:`VELOCITY`, :data:`ATTITUDE`, :data:`RATES`,
:data:`ROTORS` of :data:`STATE_SIZE`).
"""

from quadnav.vehicle.dynamics import (
    ATTITUDE,
    POSITION,
    RATES,
    ROTORS,
    STATE_SIZE,
    VELOCITY,
    VehicleArrays,
    vehicle_arrays,
)
from quadnav.vehicle.params import PRESETS, VehicleParams, load_params, preset_names

__all__ = [
    "ATTITUDE",
    "POSITION",
    "PRESETS",
    "RATES",
    "ROTORS",
    "STATE_SIZE",
    "VELOCITY",
    "VehicleArrays",
    "VehicleParams",
    "load_params",
    "preset_names",
    "vehicle_arrays",
]
