"""Controllers: the contract every controller keeps (:mod:`.contract`), the PX4-style
cascade (:mod:`.cascade`, gains and limits in :mod:`.gains`), the geometric SE(3)
controller (:mod:`.se3`), plain-Python controllers in rotorpy's shape (:mod:`.plain`) and
the registry naming them all (:mod:`.registry`).

What a controller of one's own needs is here (``examples/custom_controller.py``):
:class:`Controller` and the contract's constants, the SE(3) step to build on, and
:data:`CONTROLLERS` (or :func:`register_controller`) to name it.
"""

from quadnav.control.contract import (
    REFERENCE_ACCELERATION,
    REFERENCE_POSITION,
    REFERENCE_SIZE,
    REFERENCE_VELOCITY,
    REFERENCE_YAW,
    REFERENCE_YAW_RATE,
    SATURATED,
    Controller,
)
from quadnav.control.registry import (
    CONTROLLERS,
    ControllerFactory,
    make_controller,
    register_controller,
)
from quadnav.control.se3 import SE3GainArrays, SE3Gains, se3_gain_arrays, se3_step

__all__ = [
    "CONTROLLERS",
    "REFERENCE_ACCELERATION",
    "REFERENCE_POSITION",
    "REFERENCE_SIZE",
    "REFERENCE_VELOCITY",
    "REFERENCE_YAW",
    "REFERENCE_YAW_RATE",
    "SATURATED",
    "Controller",
    "ControllerFactory",
    "SE3GainArrays",
    "SE3Gains",
    "make_controller",
    "register_controller",
    "se3_gain_arrays",
    "se3_step",
]
