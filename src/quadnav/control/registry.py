"""Controllers by name (``--controller``): ``cascade`` (PX4-style, the default) and ``se3``
(the geometric controller), plus any registered with ``CONTROLLERS.register(name,
factory)`` or declared by an installed package's ``quadnav.controllers`` entry point.

A factory takes the cascade's :class:`~quadnav.control.gains.Gains` (what ``--gains``
and the vehicle presets set) and returns a :class:`~quadnav.control.contract.Controller`;
a controller with gains of its own ignores them.
"""

from __future__ import annotations

from collections.abc import Callable

from quadnav.control.cascade import cascade_controller
from quadnav.control.contract import Controller
from quadnav.control.gains import Gains
from quadnav.control.se3 import se3_controller
from quadnav.plugins import Registry

#: ``factory(gains) -> Controller``.
ControllerFactory = Callable[[Gains], Controller]
#: Every controller by name, the default first.
CONTROLLERS: Registry[ControllerFactory] = Registry(
    "controller", "quadnav.controllers",
    {"cascade": cascade_controller, "se3": lambda gains: se3_controller()})
#: The controller used when none is named.
DEFAULT_CONTROLLER = "cascade"
