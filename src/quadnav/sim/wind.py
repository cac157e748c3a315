"""Wind models in rotorpy's shape (``--wind SPEC``, :attr:`SimSettings.wind_model
<quadnav.sim.settings.SimSettings.wind_model>`): :func:`load_wind`.

A wind model is a class, built with the spec's literal keyword arguments, with
``update(t, position) -> wind velocity (3,) m/s`` in the world frame, as rotorpy's
``wind/wind_template.py`` (rotorpy's own winds fly unchanged:
``rotorpy.wind.default_winds:SinusoidWind(amplitudes=[1, 0, 0])``). It is named as a plug-in
(:meth:`~quadnav.plugins.Registry.load`): ``module:Class`` or ``path/to/file.py:Class``, a
name registered in :data:`WINDS` or an installed package's ``quadnav.winds`` entry point.

The simulation asks it for the wind at the vehicle's position once per control step and
holds it over the step; the vehicle's drag acts on its airspeed (its velocity less the
wind's, :mod:`quadnav.vehicle.dynamics`), beside the steady force and the gusts. A class
without ``update``, or one whose constructor raises, cannot be used (exit code 2); an
``update`` that raises or returns anything but three finite numbers fails the flight
(:class:`~quadnav.plugins.PluginError`, exit code :data:`~quadnav.plugins.FLIGHT_FAILED`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.plugins import FLIGHT_FAILED, PluginError, Registry, user_traceback

#: Wind models by name: none built in; registered ones and entry points.
WINDS: Registry = Registry("wind", "quadnav.winds", {})


class WindModel:
    """A built wind model, checked as it blows.

    Args:
        text: the spec it was named by, for messages.
        model: the built object, with ``update(t, position)``.
    """

    def __init__(self, text: str, model: Any) -> None:
        self.text = text
        self.model = model

    def at(self, t: float, position: FloatArray) -> FloatArray:
        """The wind's velocity (3,) m/s at ``t`` s at ``position`` (3,) m (a copy is
        handed over)."""
        try:
            value = self.model.update(t, np.array(position, dtype=np.float64))
            wind = np.asarray(value, dtype=np.float64).reshape(-1)
        except Exception as error:
            raise PluginError(f"wind {self.text}: {type(error).__name__} in update at t = "
                              f"{t:.3f} s: {error}", details=user_traceback(error),
                              exit_code=FLIGHT_FAILED) from None
        if wind.size != 3 or not np.all(np.isfinite(wind)):
            raise PluginError(f"wind {self.text}: update returned {value!r} at t = {t:.3f} "
                              "s, expected the wind's velocity: 3 finite numbers, m/s",
                              exit_code=FLIGHT_FAILED)
        return wind


def wind_maker(text: str) -> tuple[Callable[..., Any], Mapping[str, Any]]:
    """What builds the wind model ``text`` names (its class, or a function) and the keyword
    arguments to build it with, loaded and checked but not built.

    Raises:
        QuadnavError: an unknown name, a spec that cannot be loaded, a class without
            ``update``.
    """
    found, kwargs = WINDS.load(text)
    if isinstance(found, type) and not callable(getattr(found, "update", None)):
        raise QuadnavError(f"wind {text}: {found.__name__} has no method update(t, position)")
    return found, kwargs


def load_wind(text: str) -> WindModel:
    """The wind model ``text`` names, built with its keyword arguments (a new one on every
    call: its state starts afresh).

    Raises:
        QuadnavError: as :func:`wind_maker`, or an object built without ``update``; a
            :class:`~quadnav.plugins.PluginError` with the traceback when building it
            raised.
    """
    found, kwargs = wind_maker(text)
    try:
        model = found(**kwargs)
    except Exception as error:
        raise PluginError(f"wind {text}: {type(error).__name__} while building it: {error}",
                          details=user_traceback(error)) from None
    if not callable(getattr(model, "update", None)):
        raise QuadnavError(f"wind {text}: it built {type(model).__name__}, which has no "
                           "method update(t, position)")
    return WindModel(text, model)
