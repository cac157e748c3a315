"""Plain-Python controllers in rotorpy's shape, flown by the compiled closed loop.

A controller is a class built with the vehicle's parameter dict
(:func:`~quadnav.vehicle.rotorpy_params.rotorpy_params`) and keyword arguments of its own,
with ``update(t, state, flat_output) -> dict``, as rotorpy's
``controllers/controller_template.py``: ``state`` has ``x``, ``v``, ``q`` (i, j, k, w),
``w``, ``wind``, ``rotor_speeds``; ``flat_output`` has ``x``, ``x_dot``, ``x_ddot``,
``x_dddot``, ``x_ddddot``, ``yaw``, ``yaw_dot`` (:mod:`.rotorpy_shape`). What it returns is
read as one of rotorpy's control abstractions (:data:`ABSTRACTIONS`), flown through
quadnav's own inner loops (:mod:`.held`).

The abstraction is the ``control_abstraction`` keyword of the spec (taken by quadnav, not
passed to the class), else the class's ``control_abstraction`` attribute, else the first in
:data:`ABSTRACTIONS` whose keys the first ``update`` returns all of (rotorpy's
``SE3Control`` returns every key: it flies by motor speeds, as in rotorpy by default). The
flight then holds to it.

A class without ``update``, or whose constructor raises, cannot be used (QuadnavError,
:class:`~quadnav.plugins.PluginError` with its traceback, exit code 2). An ``update`` that
raises, returns no dict, lacks the abstraction's keys or returns commands of the wrong size
or not finite fails the flight (:class:`~quadnav.plugins.PluginError`, exit code 1): one
line naming the controller's spec, the call (its time) and what was wrong, with the
controller's own traceback when it raised. The spec's keyword arguments reach the class
with their lists of numbers as numpy arrays (:func:`~quadnav.plugins.literal_arrays`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.control.contract import Controller
from quadnav.control.gains import Gains
from quadnav.control.held import (
    MOTOR_SPEEDS,
    MOTOR_THRUSTS,
    THRUST_ATTITUDE,
    THRUST_MOMENT,
    THRUST_RATES,
    VELOCITY,
    held_controller,
    hold,
)
from quadnav.control.rotorpy_shape import flat_outputs, quaternion_from_rotorpy, state_dict
from quadnav.errors import QuadnavError
from quadnav.plugins import PluginError, literal_arrays, raised_in
from quadnav.vehicle.params import VehicleParams
from quadnav.vehicle.rotorpy_params import rotorpy_params

#: rotorpy's control abstractions, in the order one is chosen from what ``update``
#: returns: the command mode of :mod:`.held` and the keys it reads.
ABSTRACTIONS: dict[str, tuple[int, tuple[str, ...]]] = {
    "cmd_motor_speeds": (MOTOR_SPEEDS, ("cmd_motor_speeds",)),
    "cmd_motor_thrusts": (MOTOR_THRUSTS, ("cmd_motor_thrusts",)),
    "cmd_ctbm": (THRUST_MOMENT, ("cmd_thrust", "cmd_moment")),
    "cmd_ctatt": (THRUST_ATTITUDE, ("cmd_thrust", "cmd_q")),
    "cmd_ctbr": (THRUST_RATES, ("cmd_thrust", "cmd_w")),
    "cmd_vel": (VELOCITY, ("cmd_v",)),
}
#: The control abstractions whose commands fly through the cascade's loops at the control
#: rate, each saying whether its attitude loop is one of them (a body-rate command flies
#: through the rate loop alone).
INNER_LOOP_ABSTRACTIONS = {"cmd_ctatt": True, "cmd_ctbr": False, "cmd_vel": True}
#: How many numbers each command key holds.
SIZES = {"cmd_motor_speeds": 4, "cmd_motor_thrusts": 4, "cmd_thrust": 1, "cmd_moment": 3,
         "cmd_q": 4, "cmd_w": 3, "cmd_v": 3}
#: What messages call a controller.
KIND = "controller"
#: The keyword of a spec that quadnav takes as the control abstraction.
ABSTRACTION_KEYWORD = "control_abstraction"
_EXPECTED = ("cmd_motor_speeds, cmd_motor_thrusts, cmd_thrust with cmd_moment, cmd_q or "
             "cmd_w, or cmd_v")


def checked_abstraction(text: str, cls: type, kwargs: Mapping[str, Any]) -> str | None:
    """The control abstraction that the controller class ``cls``, named by the spec ``text``
    with keyword arguments ``kwargs``, flies by (None: chosen from its first ``update``),
    once it is checked to be a controller. QuadnavError (exit code 2) for a class without
    ``update`` or an unknown abstraction."""
    abstraction = kwargs.get(ABSTRACTION_KEYWORD, getattr(cls, ABSTRACTION_KEYWORD, None))
    if abstraction is not None and abstraction not in ABSTRACTIONS:
        raise QuadnavError(f"{KIND} {text}: {ABSTRACTION_KEYWORD} must be one of "
                           f"{', '.join(ABSTRACTIONS)}, got {abstraction!r}")
    if not callable(getattr(cls, "update", None)):
        raise QuadnavError(f"{KIND} {text}: {cls.__name__} has no method "
                           "update(t, state, flat_output)")
    return abstraction


def plain_controller(text: str, cls: type, kwargs: Mapping[str, Any], vehicle: VehicleParams,
                     gains: Gains) -> Controller:
    """The controller class ``cls``, named by the spec ``text`` with keyword arguments
    ``kwargs``, built with ``vehicle``'s parameter dict, as a
    :class:`~quadnav.control.contract.Controller` whose inner loops have the cascade's
    ``gains`` (those tuned for the vehicle unless given:
    :func:`~quadnav.control.registry.controller_gains`). QuadnavError (exit code 2) when it
    cannot be used (see :func:`checked_abstraction`; a constructor that raises is a
    :class:`~quadnav.plugins.PluginError` with its traceback)."""
    abstraction = checked_abstraction(text, cls, kwargs)
    arguments = literal_arrays({key: value for key, value in kwargs.items()
                                if key != ABSTRACTION_KEYWORD})
    try:
        instance = cls(rotorpy_params(vehicle), **arguments)
    except Exception as error:
        raise raised_in(KIND, text, "building it", error, exit_code=2) from None
    return held_controller(text, PlainController(text, instance, abstraction), gains)


class PlainController:
    """The Python side of a plain-Python controller
    (:class:`~quadnav.control.contract.PythonSide`): calls its ``update`` before each
    control step and holds what it returns for the compiled step.

    Args:
        text: the spec it was named by, for messages.
        controller: the built controller (an object with ``update``).
        abstraction: a key of :data:`ABSTRACTIONS`, or None to choose one from the first
            ``update``'s keys.
    """

    def __init__(self, text: str, controller: Any, abstraction: str | None) -> None:
        self.text = text
        self.controller = controller
        self.abstraction = abstraction

    def before_step(self, memory: FloatArray, t: float, state: FloatArray,
                    reference: FloatArray, jerk_snap: FloatArray, wind: FloatArray) -> None:
        """Call ``update`` and hold its commands in ``memory`` (see
        :class:`~quadnav.control.contract.PythonSide`)."""
        call = f"update({t:.6g}, state, flat_output)"
        try:
            commands = self.controller.update(t, state_dict(state, wind),
                                              flat_outputs(reference, jerk_snap))
        except Exception as error:
            raise raised_in(KIND, self.text, call, error) from None
        mode, values = self._read(commands, call)
        hold(memory, mode, values)

    def _failure(self, call: str, what: str) -> PluginError:
        return PluginError(f"{KIND} {self.text}: {call} returned {what}", exit_code=1)

    def _read(self, commands: object, call: str) -> tuple[int, FloatArray]:
        """The command mode and numbers of what the ``call`` of ``update`` returned."""
        if not isinstance(commands, Mapping):
            raise self._failure(call, f"{type(commands).__name__}: expected a dict of "
                                      f"commands: {_EXPECTED}")
        if self.abstraction is None:
            self.abstraction = next(
                (name for name, (_, keys) in ABSTRACTIONS.items()
                 if all(key in commands for key in keys)), None)
            if self.abstraction is None:
                got = ", ".join(map(str, commands)) or "nothing"
                raise self._failure(call, f"{got}: expected the commands of a control "
                                          f"abstraction: {_EXPECTED}")
        mode, keys = ABSTRACTIONS[self.abstraction]
        missing = [key for key in keys if key not in commands]
        if missing:
            raise self._failure(call, f"no {' or '.join(missing)} (it gave "
                                      f"{', '.join(map(str, commands)) or 'nothing'}): "
                                      f"flying by {self.abstraction}, expected "
                                      f"{' and '.join(keys)}")
        values = [self._numbers(key, commands[key], call) for key in keys]
        if mode == THRUST_ATTITUDE:
            size = float(np.linalg.norm(values[1]))
            if size == 0.0:
                raise self._failure(call, "cmd_q = 0: expected a quaternion (i, j, k, w)")
            values[1] = quaternion_from_rotorpy(values[1] / size)
        return mode, np.concatenate(values)

    def _numbers(self, key: str, value: object, call: str) -> FloatArray:
        """``value`` as the (SIZES[key],) float array of ``key``, checked finite."""
        try:
            numbers = np.asarray(value, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            raise self._failure(call, f"{key} = {str(value)[:40]!r}: expected "
                                      f"{SIZES[key]} number(s)") from None
        if numbers.size != SIZES[key]:
            raise self._failure(call, f"{key} of {numbers.size} number(s): expected "
                                      f"{SIZES[key]}")
        if not np.all(np.isfinite(numbers)):
            raise self._failure(call, f"a non-finite {key}: "
                                      f"{np.array2string(numbers, precision=4)}")
        return numbers
