"""Controllers by name or spec (``--controller``): ``cascade`` (PX4-style, the default) and
``se3`` (the geometric controller), plus any registered with ``CONTROLLERS.register(name,
controller)`` or declared by an installed package's ``quadnav.controllers`` entry point,
or named where it is, ``module:NAME`` or ``path/to/file.py:NAME`` with literal keyword
arguments (:meth:`~quadnav.plugins.Registry.load`).

Either kind is named, configured and reported the same way (:func:`make_controller`):

- a compiled controller's factory, ``factory(vehicle, gains=None, **kwargs) ->``
  :class:`~quadnav.control.contract.Controller`, given the vehicle and the controller's own
  gains (``None``: those tuned for that vehicle). The built-in controllers are
  :class:`GainedController`\\ s, which also know the type of their gains (a config
  dataclass: :class:`~quadnav.control.gains.Gains`, :class:`~quadnav.control.se3.SE3Gains`)
  and the gain sets they ship;
- a plain-Python controller's class, in rotorpy's shape (a class with
  ``update(t, state, flat_output)``, :mod:`quadnav.control.plain`), built with the vehicle's
  rotorpy parameter dict. Its attitude, rate and velocity commands fly through the
  cascade's inner loops, so its gains are the cascade's (:data:`INNER_LOOPS`).

A vehicle names its gain set (``VehicleParams.gains``, e.g. ``rbe595``); each controller
flies its own set of that name, or its defaults where it ships none. A gains file
(``--gains``) sets any of the controller's keys on top (:func:`controller_gains`); a
compiled controller without a gain table of its own refuses one.

A control rate is checked against the loops that run at it, for every flight, before it
(:func:`check_controller_rate`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from quadnav.config import from_table
from quadnav.control.cascade import cascade_controller, gain_arrays
from quadnav.control.contract import Controller
from quadnav.control.gains import CASCADE_SETS, Gains, gain_set, gain_table, toml_names
from quadnav.control.plain import INNER_LOOP_ABSTRACTIONS, checked_abstraction, plain_controller
from quadnav.control.sampling import check_control_rate, check_loops, gain_loops
from quadnav.control.se3 import SE3Gains, se3_controller
from quadnav.errors import QuadnavError
from quadnav.plugins import Registry, literal_arrays, raised_in
from quadnav.vehicle.params import VehicleParams

#: ``factory(vehicle, gains=None, **kwargs) -> Controller``, or a plain-Python
#: controller's class.
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
        return self.build(self.checked(vehicle, gains))

    def checked(self, vehicle: VehicleParams, gains: Any = None) -> Any:
        """``gains``, or :meth:`vehicle_gains` when None; QuadnavError for gains of another
        type."""
        if gains is None:
            return self.vehicle_gains(vehicle)
        if not isinstance(gains, self.gains_type):
            raise QuadnavError(f"expected gains of type {self.gains_type.__name__}, got "
                               f"{type(gains).__name__}")
        return gains

    def vehicle_gains(self, vehicle: VehicleParams) -> Any:
        """The gains tuned for ``vehicle``: the set its ``gains`` names, else the defaults.
        QuadnavError for a name no controller ships (:func:`gain_set_names`)."""
        if vehicle.gains not in gain_set_names():
            raise QuadnavError(f"the {vehicle.name} vehicle names the gain set "
                               f"{vehicle.gains!r}; expected one of "
                               f"{', '.join(gain_set_names())}")
        return gain_set(self.gains_type(), self.sets, vehicle.gains)


#: The cascade: the default controller, and the inner loops a plain-Python controller's
#: attitude, rate and velocity commands fly through (:mod:`quadnav.control.held`), whose
#: gains are therefore that controller's gains.
INNER_LOOPS = GainedController(cascade_controller, Gains, CASCADE_SETS)
#: The built-in controllers by name, the default first.
_OURS = {"cascade": INNER_LOOPS,
         "se3": GainedController(se3_controller, SE3Gains, "presets/se3")}
#: Every controller by name: ours, those of installed packages' entry points, those
#: registered.
CONTROLLERS: Registry[ControllerFactory] = Registry("controller", "quadnav.controllers", _OURS)
#: The controller used when none is named.
DEFAULT_CONTROLLER = "cascade"


def register_controller(name: str, factory: ControllerFactory, replace: bool = False) -> None:
    """Make ``factory`` (a compiled controller's factory or a plain-Python controller's
    class) known as ``name`` in this process, wherever a controller is chosen by name (see
    :meth:`quadnav.plugins.Registry.register`)."""
    CONTROLLERS.register(name, factory, replace)


def gain_set_names() -> list[str]:
    """Every gain set a vehicle may name: ``tello`` (every controller's defaults) and each
    set a built-in controller ships."""
    names = {DEFAULT_GAIN_SET}
    for factory in _OURS.values():
        names.update(toml_names(factory.sets))
    return sorted(names)


def _gains_of(found: Any) -> GainedController | None:
    """Whose gains the loaded controller ``found`` flies with: its own
    (a :class:`GainedController`), the cascade's inner loops' (a plain-Python controller's
    class), or None (a compiled factory without a gain table of its own)."""
    if isinstance(found, GainedController):
        return found
    return INNER_LOOPS if isinstance(found, type) else None


def controller_class(text: str) -> type | None:
    """The plain-Python controller's class that ``text`` names, loaded and checked (it has
    ``update`` and a known control abstraction) but not built, or None when ``text`` names a
    compiled controller's factory: the check of a controller's name or spec before any
    work.

    Raises:
        QuadnavError: an unknown name, a spec that cannot be loaded, a class that is not a
            controller (:func:`~quadnav.control.plain.checked_abstraction`).
    """
    found, kwargs = CONTROLLERS.load(text)
    if not isinstance(found, type):
        return None
    checked_abstraction(text, found, kwargs)
    return found


def controller_gains(controller: str, vehicle: VehicleParams,
                     source: str | Path | Mapping[str, Any] | None = None,
                     where: str = "gains") -> Any:
    """The gains ``controller`` flies ``vehicle`` with: those tuned for the vehicle, with the
    keys of ``source`` set on top (a course gain table's name, a gains TOML file, or a table
    of keys, named ``where`` in messages). A plain-Python controller's are the cascade's
    (its inner loops'); None for a compiled controller without gains of its own.

    Raises:
        QuadnavError: an unknown controller, a bad key or value (naming the file and key),
            or a ``source`` for a controller without gains.
    """
    owner = _gains_of(CONTROLLERS.load(controller)[0])
    if owner is None:
        if source is not None:
            raise QuadnavError(f"controller {controller}: it has no gain table to set "
                               f"(gains {source if isinstance(source, str | Path) else 'table'}"
                               " given)")
        return None
    gains = owner.vehicle_gains(vehicle)
    if source is None:
        return gains
    if isinstance(source, Mapping):
        return from_table(gains, dict(source), where)
    return from_table(gains, *gain_table(source))


def make_controller(text: str, vehicle: VehicleParams, gains: Any = None) -> Controller:
    """The controller ``text`` names, ready to fly ``vehicle`` (as its controller knows it)
    with ``gains`` (None: those tuned for the vehicle, :func:`controller_gains`): a
    compiled controller's factory called with them and the spec's keyword arguments, or a
    plain-Python controller's class built with ``vehicle``'s rotorpy parameter dict, its
    inner loops flying with them. A new one on every call: a Python controller's state
    starts afresh.

    Raises:
        QuadnavError: an unknown name, a spec that cannot be loaded, gains of another
            controller, a class without ``update``, a factory that does not return a
            Controller; a :class:`~quadnav.plugins.PluginError` with the traceback when the
            user's code raised while building it.
    """
    found, kwargs = CONTROLLERS.load(text)
    if isinstance(found, type):
        return plain_controller(text, found, kwargs, vehicle,
                                INNER_LOOPS.checked(vehicle, gains))
    try:
        controller = found(vehicle, gains, **literal_arrays(kwargs))
    except QuadnavError:
        raise
    except Exception as error:
        raise raised_in("controller", text, "building it", error, exit_code=2) from None
    if not isinstance(controller, Controller):
        raise QuadnavError(f"controller {text}: expected a class with update(t, state, "
                           "flat_output), or a function of the vehicle and gains returning "
                           "a quadnav.control.contract.Controller; it returned "
                           f"{type(controller).__name__}")
    return controller


def check_controller_rate(text: str, vehicle: VehicleParams, gains: Any, control_rate: float,
                          plant: VehicleParams | None = None) -> None:
    """Refuse a ``control_rate`` Hz at which a loop that runs at it is unstable on ``plant``
    (default: ``vehicle``), and warn of one that leaves it little gain margin
    (:func:`~quadnav.control.sampling.check_loops`): the loops of the controller ``text``
    names, a compiled one built for ``vehicle`` with ``gains`` (None: those tuned for it),
    or, under a plain-Python controller (not built), the cascade's loops that its control
    abstraction flies through with those gains (:data:`~quadnav.control.plain.
    INNER_LOOP_ABSTRACTIONS`). A plain-Python controller that commands the rotors or the
    wrench itself, or leaves its abstraction to its first ``update``, has no loops here to
    check. The one check of a flight's control rate: missions, tracking and kinodynamic
    flights make it before they fly.

    Raises:
        QuadnavError: an unknown controller or one that cannot be used (as
            :func:`make_controller`), gains of another type, or a rate at which a loop is
            unstable.
    """
    found, kwargs = CONTROLLERS.load(text)
    flown = plant or vehicle
    if not isinstance(found, type):
        check_control_rate(make_controller(text, vehicle, gains), flown, control_rate)
        return
    abstraction = checked_abstraction(text, found, kwargs)
    inner = INNER_LOOPS.checked(vehicle, gains)
    if abstraction in INNER_LOOP_ABSTRACTIONS:
        check_loops(gain_loops(gain_arrays(inner), INNER_LOOP_ABSTRACTIONS[abstraction]),
                    f"the {text} controller's", flown, control_rate,
                    f" (the cascade's, flying its {abstraction} commands)")
