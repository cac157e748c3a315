"""The controller contract: what the closed loop (:mod:`quadnav.sim.loop`), the Tello
emulator and any controller agree on, so a new controller flies without editing them.

A controller is one compiled step (a numba ``@njit`` function)::

    step(memory (M,), state (17,), reference (11,), gains, vehicle, dt) -> commands (4,)

- ``memory``: the controller's own float64 array (integrals, filters, previous values),
  updated in place; slot :data:`SATURATED` is 1.0 after a step whose commands had to be
  clipped (the loop reports the share of such steps) and 0.0 otherwise.
- ``state``: the measured vehicle state (:mod:`quadnav.vehicle.dynamics`: position,
  velocity, quaternion (w, x, y, z), body rates, rotor speeds; its slices
  :data:`~quadnav.vehicle.dynamics.POSITION`, ``VELOCITY``, ``ATTITUDE``, ``RATES``,
  ``ROTORS``).
- ``reference``: the row the loop tracks (:data:`REFERENCE_SIZE`,): position (3) m,
  velocity (3) m/s, acceleration (3) m/s^2, yaw rad, yaw rate rad/s (its columns
  :data:`REFERENCE_POSITION`, :data:`REFERENCE_VELOCITY`, :data:`REFERENCE_ACCELERATION`,
  :data:`REFERENCE_YAW`, :data:`REFERENCE_YAW_RATE`).
- ``gains``: the controller's compiled gains, any value numba can pass (an array, a
  NamedTuple of arrays and floats), of one type.
- ``vehicle``: the vehicle as the controller knows it
  (:class:`~quadnav.vehicle.dynamics.VehicleArrays`: mass, inertia, mixer, ...).
- ``dt``: seconds since the last step; the commands are motor commands in [0, 1].

:class:`Controller` bundles a step with its gains and memory size;
``examples/custom_controller.py`` is a template, :mod:`quadnav.control.cascade` and
:mod:`quadnav.control.se3` are the built-in ones (``--controller``).

A plain-Python controller (:mod:`quadnav.control.plain`) is a Controller too:
its compiled step (:mod:`quadnav.control.held`) flies the commands that its Python side
(:class:`PythonSide`) holds in its memory, set before each control step; the closed loop
then runs one control step per call (:func:`quadnav.sim.simulate.simulate`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numba
import numpy as np
from numba import types

from quadnav.arrays import FloatArray

#: The memory slot that says whether the last step's commands were clipped.
SATURATED = 0

#: Length of a reference row, and the columns of each quantity in it (numba kernels
#: read these module-level constants as compile-time constants).
REFERENCE_SIZE = 11
#: Position (3,) m.
REFERENCE_POSITION = slice(0, 3)
#: Velocity (3,) m/s.
REFERENCE_VELOCITY = slice(3, 6)
#: Acceleration (3,) m/s^2.
REFERENCE_ACCELERATION = slice(6, 9)
#: Yaw, rad.
REFERENCE_YAW = 9
#: Yaw rate, rad/s.
REFERENCE_YAW_RATE = 10


class PythonSide(Protocol):
    """The Python half of a controller, run before each of its compiled steps."""

    def before_step(self, memory: FloatArray, t: float, state: FloatArray,
                    reference: FloatArray, jerk_snap: FloatArray, wind: FloatArray) -> None:
        """Set in ``memory`` what the compiled step flies next, at ``t`` s, for the measured
        ``state`` (17,), the ``reference`` row (11,), the reference's jerk and snap (6,),
        m/s^3 and m/s^4, and the wind's velocity (3,) m/s."""
        ...


@dataclass(frozen=True, eq=False)
class Controller:
    """A compiled controller, ready to fly.

    Attributes:
        name: how it is reported, e.g. ``"cascade"``, or the spec it was named by.
        step: the compiled step (see the module docstring).
        gains: its compiled gains, passed to every step.
        memory_size: length of its memory array (at least 1: slot :data:`SATURATED`).
        python: for a plain-Python controller, its Python side, run before every step;
            None for a compiled one.
    """

    name: str
    step: Any
    gains: Any
    memory_size: int
    python: PythonSide | None = None

    def new_memory(self) -> FloatArray:
        """Fresh memory: every slot 0."""
        return np.zeros(max(self.memory_size, SATURATED + 1))

    def function_type(self, vehicle: Any) -> types.FunctionType:
        """The numba type of :attr:`step` for these gains and ``vehicle``: the compiled
        loop takes the step as a function of this type, so one compiled loop (cached on
        disk) serves every controller with gains of the same type."""
        array = types.float64[::1]
        return types.FunctionType(array(array, array, array, numba.typeof(self.gains),
                                        numba.typeof(vehicle), types.float64))

    def compiled_step(self, vehicle: Any) -> Any:
        """:attr:`step` compiled for :meth:`function_type` (numba's compile result), loaded
        from numba's cache on disk when the step is cached there (``@njit(cache=True)``).

        A cache entry names the module its function was compiled in, and loading it
        imports that module again. One file run as a script (module ``__main__``) and
        loaded as a plug-in (``file.py:Name``, module ``quadnav_plugin_...``) shares one
        cache entry but not the module's name, so the entry one of them wrote cannot be
        loaded in the other's process (numba raises ImportError). Such an entry is
        dropped and the step compiled again, which writes an entry loadable here.
        """
        signature = self.function_type(vehicle).signature
        try:
            return self.step.get_compile_result(signature)
        except ImportError:
            self.step._cache.flush()  # numba's only handle on a dispatcher's disk cache
            return self.step.get_compile_result(signature)
