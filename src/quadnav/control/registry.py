"""Controllers by name or spec (``--controller``): ``cascade`` (PX4-style, the default) and
``se3`` (the geometric controller), plus any registered with ``CONTROLLERS.register(name,
controller)`` or declared by an installed package's ``quadnav.controllers`` entry point,
or named where it is, ``module:NAME`` or ``path/to/file.py:NAME`` with literal keyword
arguments (:meth:`~quadnav.plugins.Registry.load`).

Either kind is named, configured and reported the same way (:func:`make_controller`):

- a compiled controller's factory, ``factory(gains, **kwargs) ->``
  :class:`~quadnav.control.contract.Controller`, given the cascade's
  :class:`~quadnav.control.gains.Gains` (what ``--gains`` and the vehicle presets set; a
  controller with gains of its own ignores them);
- a plain-Python controller's class, in rotorpy's shape (a class with
  ``update(t, state, flat_output)``, :mod:`quadnav.control.plain`).
"""

from __future__ import annotations

from collections.abc import Callable

from quadnav.control.cascade import cascade_controller
from quadnav.control.contract import Controller
from quadnav.control.gains import Gains
from quadnav.control.plain import checked_abstraction, plain_controller
from quadnav.control.se3 import se3_controller
from quadnav.errors import QuadnavError
from quadnav.plugins import Registry, literal_arrays, raised_in
from quadnav.vehicle.params import VehicleParams

#: ``factory(gains) -> Controller``, or a plain-Python controller's class.
ControllerFactory = Callable[..., Controller]
#: Every controller by name, the default first.
CONTROLLERS: Registry[ControllerFactory] = Registry(
    "controller", "quadnav.controllers",
    {"cascade": cascade_controller, "se3": lambda gains: se3_controller()})
#: The controller used when none is named.
DEFAULT_CONTROLLER = "cascade"


def controller_class(text: str) -> type | None:
    """The plain-Python controller's class that ``text`` names, loaded and checked (it has
    ``update`` and a known control abstraction) but not built, or None when ``text`` names a
    compiled controller's factory.

    Raises:
        QuadnavError: an unknown name, a spec that cannot be loaded, a class that is not a
            controller (:func:`~quadnav.control.plain.checked_abstraction`).
    """
    found, kwargs = CONTROLLERS.load(text)
    if not isinstance(found, type):
        return None
    checked_abstraction(text, found, kwargs)
    return found


def make_controller(text: str, gains: Gains, vehicle: VehicleParams) -> Controller:
    """The controller ``text`` names, ready to fly ``vehicle`` (as its controller knows it):
    a compiled controller's factory called with ``gains`` and the spec's keyword arguments,
    or a plain-Python controller's class built with ``vehicle``'s rotorpy parameter dict
    (its inner loops with ``gains``). A new one on every call: a Python controller's state
    starts afresh.

    Raises:
        QuadnavError: an unknown name, a spec that cannot be loaded, a class without
            ``update``, a factory that does not return a Controller; a
            :class:`~quadnav.plugins.PluginError` with the traceback when the user's code
            raised while building it.
    """
    found, kwargs = CONTROLLERS.load(text)
    if isinstance(found, type):
        return plain_controller(text, found, kwargs, vehicle, gains)
    try:
        controller = found(gains, **literal_arrays(kwargs))
    except Exception as error:
        raise raised_in("controller", text, "building it", error, exit_code=2) from None
    if not isinstance(controller, Controller):
        raise QuadnavError(f"controller {text}: expected a class with update(t, state, "
                           "flat_output), or a function of the gains returning a "
                           f"quadnav.control.contract.Controller; it returned "
                           f"{type(controller).__name__}")
    return controller
