"""Controllers by name (``--controller``): ``cascade`` (PX4-style, the default) and ``se3``
(the geometric controller), plus any registered with ``CONTROLLERS.register(name,
factory)`` or declared by an installed package's ``quadnav.controllers`` entry point.

A factory takes the vehicle and the controller's own gains, ``factory(vehicle, gains=None)
-> Controller``; ``None``: the gains tuned for that vehicle. The built-in controllers are
:class:`GainedController`\\ s, which also know the type of their gains (a config dataclass:
:class:`~quadnav.control.gains.Gains`, :class:`~quadnav.control.se3.SE3Gains`) and the gain
sets they ship. A vehicle names its gain set (``VehicleParams.gains``, e.g. ``rbe595``);
each controller flies its own set of that name, or its defaults where it ships none. A gains
file (``--gains``) sets any of the controller's keys on top (:func:`controller_gains`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

from quadnav.config import from_table
from quadnav.control.cascade import cascade_controller
from quadnav.control.contract import Controller
from quadnav.control.gains import CASCADE_SETS, Gains, gain_set, gain_table, toml_names
from quadnav.control.se3 import SE3Gains, se3_controller
from quadnav.errors import QuadnavError
from quadnav.plugins import Registry
from quadnav.vehicle.params import VehicleParams

#: ``factory(vehicle, gains=None) -> Controller``.
ControllerFactory = Callable[..., Controller]
#: The name of every controller's default gains, the ``tello`` vehicle's.
DEFAULT_GAIN_SET = "tello"


@dataclass(frozen=True, eq=False)
class GainedController:
    """A controller with gains of its own: the factory of a built-in controller.

    Attributes:
        build: ``build(gains) -> Controller``.
        gains_type: its gains, a config dataclass whose defaults are the ``tello`` set
            (read from TOML by :func:`~quadnav.config.from_table`).
        sets: the folder of quadnav.control holding its gain sets, ``NAME.toml`` each.
    """

    build: Callable[[Any], Controller]
    gains_type: type
    sets: str

    def __call__(self, vehicle: VehicleParams, gains: Any = None) -> Controller:
        """The controller flying ``vehicle`` with ``gains`` (None: :meth:`vehicle_gains`)."""
        if gains is None:
            gains = self.vehicle_gains(vehicle)
        if not isinstance(gains, self.gains_type):
            raise QuadnavError(f"expected gains of type {self.gains_type.__name__}, got "
                               f"{type(gains).__name__}")
        return self.build(gains)

    def vehicle_gains(self, vehicle: VehicleParams) -> Any:
        """The gains tuned for ``vehicle``: the set its ``gains`` names, else the defaults.
        QuadnavError for a name no controller ships (:func:`gain_set_names`)."""
        if vehicle.gains not in gain_set_names():
            raise QuadnavError(f"the {vehicle.name} vehicle names the gain set "
                               f"{vehicle.gains!r}; expected one of "
                               f"{', '.join(gain_set_names())}")
        return gain_set(self.gains_type(), self.sets, vehicle.gains)


#: Every controller by name, the default first.
CONTROLLERS: Registry[ControllerFactory] = Registry("controller", "quadnav.controllers", {
    "cascade": GainedController(cascade_controller, Gains, CASCADE_SETS),
    "se3": GainedController(se3_controller, SE3Gains, "presets/se3"),
})
#: The controller used when none is named.
DEFAULT_CONTROLLER = "cascade"


def gain_set_names() -> list[str]:
    """Every gain set a vehicle may name: ``tello`` (every controller's defaults) and each
    set a built-in controller ships."""
    names = {DEFAULT_GAIN_SET}
    for name in CONTROLLERS:
        factory = CONTROLLERS.get(name)
        if isinstance(factory, GainedController):
            names.update(toml_names(factory.sets))
    return sorted(names)


def controller_factory(controller: str) -> ControllerFactory:
    """The factory ``controller`` names: a registered name, or a plug-in spec
    (:meth:`~quadnav.plugins.Registry.load`), whose keyword arguments are passed on to the
    factory. QuadnavError naming the choices for an unknown name."""
    factory, kwargs = CONTROLLERS.load(controller)
    return partial(factory, **kwargs) if kwargs else factory


def controller_gains(controller: str, vehicle: VehicleParams,
                     source: str | Path | Mapping[str, Any] | None = None,
                     where: str = "gains") -> Any:
    """The gains ``controller`` flies ``vehicle`` with: those tuned for the vehicle, with the
    keys of ``source`` set on top (a course gain table's name, a gains TOML file, or a table
    of keys, named ``where`` in messages); None for a controller without gains of its own.

    Raises:
        QuadnavError: an unknown controller, a bad key or value (naming the file and key),
            or a ``source`` for a controller without gains.
    """
    factory = CONTROLLERS.load(controller)[0]
    if not isinstance(factory, GainedController):
        if source is not None:
            raise QuadnavError(f"controller {controller}: it has no gain table to set "
                               f"(gains {source if isinstance(source, str | Path) else 'table'}"
                               " given)")
        return None
    gains = factory.vehicle_gains(vehicle)
    if source is None:
        return gains
    if isinstance(source, Mapping):
        return from_table(gains, dict(source), where)
    return from_table(gains, *gain_table(source))


def make_controller(controller: str, vehicle: VehicleParams, gains: Any = None) -> Controller:
    """The controller ``controller`` names (:func:`controller_factory`) flying ``vehicle``
    with ``gains`` (None: those tuned for the vehicle)."""
    return controller_factory(controller)(vehicle, gains)
