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
(:class:`~quadnav.plugins.PluginError`, exit code 1). The spec's keyword arguments reach
the class with their lists of numbers as numpy arrays
(:func:`~quadnav.plugins.literal_arrays`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.errors import QuadnavError
from quadnav.plugins import PluginError, Registry, literal_arrays, raised_in

#: What messages call a wind model.
KIND = "wind"
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
        call = f"update({t:.6g}, position)"
        try:
            value = self.model.update(t, np.array(position, dtype=np.float64))
        except Exception as error:
            raise raised_in(KIND, self.text, call, error) from None
        try:
            wind = np.asarray(value, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            wind = np.empty(0)
        if wind.size != 3 or not np.all(np.isfinite(wind)):
            raise PluginError(f"{KIND} {self.text}: {call} returned {str(value)[:40]!r}: "
                              "expected the wind's velocity, 3 finite numbers, m/s",
                              exit_code=1)
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
        raise QuadnavError(f"{KIND} {text}: {found.__name__} has no method update(t, position)")
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
        model = found(**literal_arrays(kwargs))
    except Exception as error:
        raise raised_in(KIND, text, "building it", error, exit_code=2) from None
    if not callable(getattr(model, "update", None)):
        raise QuadnavError(f"{KIND} {text}: it built {type(model).__name__}, which has no "
                           "method update(t, position)")
    return WindModel(text, model)
