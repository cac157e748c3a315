"""Plain-Python trajectories in rotorpy's shape: a class whose ``update(t)`` returns the
flat outputs (``rotorpy/trajectories/traj_template.py``), named where it is
(``module:Class`` or ``path/to/file.py:Class``, with literal keyword arguments,
:mod:`quadnav.plugins`), sampled once at the control rate into a
:class:`FlatOutputReference` that the closed loop flies as any reference.

* Naming: :func:`load_trajectory_class` reads the spec (a list of numbers in its arguments
  arrives as a numpy array, :func:`~quadnav.plugins.literal_arrays`) and checks that the
  class can be built with them (and with what a mission gives it, when a mission builds
  it) and has ``update``: else one line, exit 2.
* Building: :meth:`TrajectoryClass.build` makes it; in a mission, as ``fly`` does, the
  path (N, 3) m is given as ``points`` when the constructor has such a parameter and the
  spec does not set it (rotorpy's ``MinSnap(points, ...)``), and likewise the real map as
  ``world`` and the start and goal (3,) m as ``start`` and ``goal``, so that a class that
  plans for itself flies too (MEAM620's ``WorldTraj(world, start, goal)``; quadnav's
  planner still runs first, and its path is the one drawn); otherwise from the spec's
  arguments alone.
* Sampling: :func:`flat_reference` calls ``update(t)`` at every ``k dt`` (the control
  interval) and at the end. Of rotorpy's flat outputs quadnav flies ``x``, ``x_dot``,
  ``x_ddot`` ((3,) m, m/s, m/s^2, world frame, z up), ``yaw`` and ``yaw_dot`` (rad,
  rad/s); the others (``x_dddot``, ``x_ddddot``, ``yaw_ddot``) may be left out. A missing
  key, a wrong shape, something not a number, a NaN or a position beyond
  :data:`~quadnav.limits.COORDINATE` is one line naming the spec, the time and the key;
  an exception in ``update`` shows its own traceback (:class:`~quadnav.plugins.PluginError`,
  exit 1 for both: the flight failed because of the class).
* Duration: as given (``--duration``), else the class's own: a ``duration`` attribute, or
  the last of rotorpy's ``t_keyframes`` (the time of the last waypoint); a class that says
  neither needs ``--duration``. After it the reference holds still at its last position
  (every derivative 0), as every quadnav reference does, whatever ``update`` says then.

Between samples the reference is the quintic Hermite interpolation of the samples'
position, velocity and acceleration
(:func:`~quadnav.trajectory.references.sampled.sampled_reference`), exact at every sample
(to rounding), so the closed loop, which reads the reference at the same ``k dt``, flies
what ``update`` returned there; the yaw rate flown is ``yaw_dot`` as returned.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.control.contract import (
    REFERENCE_ACCELERATION,
    REFERENCE_POSITION,
    REFERENCE_SIZE,
    REFERENCE_VELOCITY,
    REFERENCE_YAW,
    REFERENCE_YAW_RATE,
)
from quadnav.errors import QuadnavError
from quadnav.limits import COORDINATE, MAX_DURATION, MAX_SAMPLES, check_count
from quadnav.plugins import (
    PluginError,
    check_call,
    literal_arrays,
    load_target,
    parse_spec,
    raised_in,
    takes_keyword,
)
from quadnav.trajectory.references.contract import Samples, sample_times
from quadnav.trajectory.references.sampled import SampledReference, sampled_reference
from quadnav.world.model import World
from quadnav.world.placement import format_point

#: The format of a :class:`FlatOutputReference` (its ``format`` and ``info["format"]``).
FORMAT = "update(t)"
#: The flat outputs flown, rotorpy's names: (3,) vectors, then numbers.
VECTORS = ("x", "x_dot", "x_ddot")
SCALARS = ("yaw", "yaw_dot")
FLOWN = (*VECTORS, *SCALARS)
#: Columns of each key in a sample row: a reference row's (x 0-2, x_dot 3-5, x_ddot 6-8,
#: yaw 9, yaw_dot 10; :mod:`quadnav.control.contract`).
_COLUMNS = {"x": REFERENCE_POSITION, "x_dot": REFERENCE_VELOCITY,
            "x_ddot": REFERENCE_ACCELERATION,
            "yaw": slice(REFERENCE_YAW, REFERENCE_YAW + 1),
            "yaw_dot": slice(REFERENCE_YAW_RATE, REFERENCE_YAW_RATE + 1)}
KIND = "reference"
#: What a mission gives a trajectory class it builds, by keyword, when its constructor has
#: such a parameter and the spec leaves it out: the planned path (N, 3) m, and the real map
#: (:class:`~quadnav.world.model.World`), start and goal (3,) m, for a class that plans for
#: itself (MEAM620's ``WorldTraj(world, start, goal)``).
MISSION_ARGUMENTS = ("points", "world", "start", "goal")


@dataclass(frozen=True, eq=False)
class FlatOutputReference(SampledReference):
    """A trajectory class sampled at the control rate (see the module docstring): a
    :class:`~quadnav.trajectory.references.sampled.SampledReference` with the yaw rate as returned
    and, in a mission, the times of its legs.

    Attributes:
        yaw_rates: (N,) ``yaw_dot`` at the samples' times, rad/s.
        window: ``(begin, end)`` s, between the legs out of the safety margin
            (:func:`leg_window`); None: none, the whole reference.
    """

    yaw_rates: FloatArray = dataclasses.field(default_factory=lambda: np.zeros(0))
    window: tuple[float, float] | None = None

    @property
    def main_window(self) -> tuple[float, float]:
        """``(begin, end)``, s: the times between the legs (all of it without legs)."""
        return (0.0, self.duration) if self.window is None else self.window

    def yaw_rate(self, t: ArrayLike) -> FloatArray:
        """Yaw rate, rad/s, at ``t`` s: linear between the samples' ``yaw_dot``, 0 before
        the start and after the end."""
        times = np.asarray(t, dtype=np.float64)
        inside = (times >= 0.0) & (times <= self.duration)
        return np.where(inside, np.interp(times, self.samples.t, self.yaw_rates), 0.0)


@dataclass(frozen=True, eq=False)
class TrajectoryClass:
    """A trajectory class as a spec names it (:func:`load_trajectory_class`).

    Attributes:
        text: the spec as given, the reference's name.
        factory: the class (or any callable returning an object with ``update(t)``).
        kwargs: the spec's keyword arguments, as the class gets them.
    """

    text: str
    factory: Callable[..., Any]
    kwargs: Mapping[str, Any]

    @property
    def mission_arguments(self) -> tuple[str, ...]:
        """Which of :data:`MISSION_ARGUMENTS` a mission gives it: those its constructor
        has a parameter for and the spec leaves out."""
        return tuple(name for name in MISSION_ARGUMENTS
                     if name not in self.kwargs and takes_keyword(self.factory, name))

    def build(self, points: ArrayLike | None = None, world: World | None = None,
              start: ArrayLike | None = None, goal: ArrayLike | None = None) -> Any:
        """The trajectory object, built with the spec's arguments and, of those given,
        the :attr:`mission_arguments`: ``points`` (N, 3) m, ``world`` (the real map),
        ``start`` and ``goal`` (3,) m. A :class:`~quadnav.plugins.PluginError` (exit 1) with
        the class's traceback when building it raises; QuadnavError when what it builds
        has no ``update``."""
        given = {"points": None if points is None else
                 np.array(points, dtype=np.float64).reshape(-1, 3),
                 "world": world,
                 "start": None if start is None else np.array(start, dtype=np.float64),
                 "goal": None if goal is None else np.array(goal, dtype=np.float64)}
        kwargs = dict(self.kwargs) | {name: given[name] for name in self.mission_arguments
                                      if given[name] is not None}
        try:
            built = self.factory(**kwargs)
        except Exception as error:
            raise raised_in(KIND, self.text, "building it", error) from None
        if not callable(getattr(built, "update", None)):
            raise QuadnavError(f"{KIND} {self.text}: what it builds ({type(built).__name__}) "
                               "has no update(t) method")
        return built


def is_trajectory_class(text: str) -> bool:
    """Whether ``text`` names something where it is (``module:Name`` or ``file.py:Name``,
    with or without arguments) rather than a built-in name."""
    try:
        return parse_spec(text, KIND).is_located
    except QuadnavError:
        return False


def load_trajectory_class(text: str, with_points: bool = False) -> TrajectoryClass:
    """The class ``text`` names (see the module docstring); ``with_points``: it will be
    built by a mission (:data:`MISSION_ARGUMENTS`). QuadnavError (exit 2) for a spec that
    is not ``module:Class`` or ``file.py:Class``, a class that cannot be found or loaded,
    cannot take the arguments, or has no ``update``."""
    spec = parse_spec(text, KIND)
    if not spec.is_located:
        raise QuadnavError(f"{KIND} {text!r}: expected a trajectory class, module:Class or "
                           "path/to/file.py:Class, optionally with keyword arguments that "
                           "are literals: Class(key=value, ...)")
    factory = load_target(spec.target, KIND)
    if not callable(factory):
        raise QuadnavError(f"{KIND} {text}: {spec.target} is a {type(factory).__name__}, "
                           "expected a class with update(t)")
    if isinstance(factory, type) and not callable(getattr(factory, "update", None)):
        raise QuadnavError(f"{KIND} {text}: {factory.__name__} has no update(t) method")
    chosen = TrajectoryClass(text, factory, literal_arrays(spec.kwargs))
    given = dict(chosen.kwargs) | (dict.fromkeys(chosen.mission_arguments) if with_points
                                   else {})
    check_call(KIND, text, factory, (), given)
    return chosen


def stated_duration(trajectory: Any) -> tuple[float, str] | None:
    """How long ``trajectory`` says it lasts, s, and where it says so (``"duration"``, or
    ``"t_keyframes"``: rotorpy's ``MinSnap``, the time of its last waypoint); None when it
    does not say."""
    duration = getattr(trajectory, "duration", None)
    if isinstance(duration, int | float | np.number) and not isinstance(duration, bool):
        return float(duration), "duration"
    keyframes = getattr(trajectory, "t_keyframes", None)
    if keyframes is not None and np.size(keyframes):
        return float(np.asarray(keyframes, dtype=np.float64).reshape(-1)[-1]), "t_keyframes"
    return None


def flat_reference(trajectory: Any, name: str, dt: float, duration: float | None = None
                   ) -> FlatOutputReference:
    """``trajectory`` (an object with ``update(t)``) sampled every ``dt`` s, the control
    interval, for ``duration`` s (None: as long as it says it lasts, :func:`stated_duration`),
    named ``name`` (its spec) in messages and reports.

    Raises:
        QuadnavError: no duration given or stated, one given not in (0, MAX_DURATION] s,
            or more than :data:`~quadnav.limits.MAX_SAMPLES` samples.
        PluginError: ``update`` raised (with its traceback) or returned what cannot be
            flown, or the class states a duration out of range (exit 1).
    """
    if duration is not None:
        source = "given"
    elif (stated := stated_duration(trajectory)) is not None:
        duration, source = stated
    else:
        raise QuadnavError(f"{KIND} {name}: {type(trajectory).__name__} does not say how long "
                           "it lasts (no duration or t_keyframes attribute): give --duration S")
    if not 0.0 < duration <= MAX_DURATION:
        said = "" if source == "given" else f" (its {source})"
        error = (f"{KIND} {name}: it lasts {duration:g} s{said}: expected more than 0 and at "
                 f"most {MAX_DURATION:g} s")
        raise QuadnavError(error) if source == "given" else PluginError(error, exit_code=1)
    check_count(duration / dt + 1, MAX_SAMPLES, f"a {duration:.6g} s trajectory class sampled "
                f"at the control rate ({1 / dt:g} Hz) gives samples",
                "shorten it (--duration) or lower --control-rate")
    times = sample_times(duration, dt)
    rows = np.empty((len(times), REFERENCE_SIZE))
    for k, t in enumerate(times):
        try:
            flat = trajectory.update(float(t))
        except Exception as error:
            raise raised_in(KIND, name, f"update({t:.6g})", error) from None
        rows[k] = _row(flat, name, float(t))
    _check_values(rows, times, name)
    samples = Samples(times, rows[:, REFERENCE_POSITION], rows[:, REFERENCE_VELOCITY],
                      rows[:, REFERENCE_ACCELERATION], rows[:, REFERENCE_YAW])
    info = {"format": FORMAT, "samples": len(times), "sample_interval_s": dt,
            "duration_s": float(duration), "duration_from": source}
    base = sampled_reference(name, FORMAT, samples, info)
    return FlatOutputReference(base.name, base.format, base.samples, base.motion, base.info,
                               yaw_rates=rows[:, REFERENCE_YAW_RATE].copy())


def _row(flat: Any, name: str, t: float) -> FloatArray:
    """The 11 numbers (x, x_dot, x_ddot, yaw, yaw_dot) of what ``update(t)`` returned;
    PluginError (exit 1) naming what is missing or of the wrong shape."""
    where = f"{KIND} {name}: update({t:.6g}) returned"
    expected = (f"expected a dict of flat outputs: {', '.join(VECTORS)} (3,) and "
                f"{', '.join(SCALARS)}")
    if not isinstance(flat, Mapping):
        raise PluginError(f"{where} {type(flat).__name__}: {expected}", exit_code=1)
    missing = [key for key in FLOWN if key not in flat]
    if missing:
        raise PluginError(f"{where} no {', '.join(missing)} (it gave "
                          f"{', '.join(map(str, flat)) or 'nothing'}): {expected}", exit_code=1)
    row = np.empty(REFERENCE_SIZE)
    for key in FLOWN:
        try:
            value = np.asarray(flat[key], dtype=np.float64)
        except (TypeError, ValueError):
            raise PluginError(f"{where} {key} = {str(flat[key])[:40]!r}: expected numbers",
                              exit_code=1) from None
        shape = (3,) if key in VECTORS else ()
        if value.shape != shape and not (key in SCALARS and value.shape == (1,)):
            raise PluginError(f"{where} {key} of shape {value.shape}: expected "
                              f"{'(3,)' if shape else 'a number'}", exit_code=1)
        row[_COLUMNS[key]] = value.reshape(-1)
    return row


def _check_values(rows: FloatArray, times: FloatArray, name: str) -> None:
    """PluginError (exit 1) naming the first sample, and its key, that is not finite or
    whose position lies beyond :data:`~quadnav.limits.COORDINATE`."""
    bad = ~np.isfinite(rows)
    position = _COLUMNS["x"]
    bad[:, position] |= np.abs(np.nan_to_num(rows[:, position])) > COORDINATE.high
    if not bad.any():
        return
    k, column = (int(i) for i in np.argwhere(bad)[0])
    key = next(key for key, columns in _COLUMNS.items()
               if columns.start <= column < columns.stop)
    values = rows[k, _COLUMNS[key]]
    shown = format_point(values) if key in VECTORS else f"{values[0]:g}"
    expected = (f"a position {COORDINATE.describe()}" if key == "x" and np.isfinite(values).all()
                else "finite numbers")
    raise PluginError(f"{KIND} {name}: update({times[k]:.6g}) returned {key} {shown}: "
                      f"expected {expected}", exit_code=1)


def check_ends(reference: FlatOutputReference, start: FloatArray, goal: FloatArray,
               tolerance: float) -> None:
    """PluginError (exit 1) unless ``reference`` starts within ``tolerance`` m of ``start``
    (3,) and ends within it of ``goal`` (3,): a mission's reference flies from its start to
    its goal."""
    for label, t, point in (("starts", 0.0, start), ("ends", reference.duration, goal)):
        at = reference.position(t)
        off = float(np.linalg.norm(at - point))
        if off > tolerance:
            where = "start" if label == "starts" else "goal"
            raise PluginError(f"{KIND} {reference.name} {label} at {format_point(at)}, "
                              f"{off:.3g} m from the {where} {format_point(point)} (the goal "
                              f"tolerance is {tolerance:g} m): a mission's reference flies "
                              "from its start to its goal", exit_code=1)


def leg_window(reference: FlatOutputReference, inflated: World, start_leg: bool,
               goal_leg: bool) -> tuple[float, float]:
    """The times between the legs of ``reference`` in a mission, s, as quadnav's own
    trajectories have them: with a leg out of the margin at the start (``start_leg``), from
    its first sample free in the map inflated by the margin (``inflated``), else from 0;
    with one at the goal, to its last such sample, else to the end. The whole reference
    when no sample is free."""
    t, duration = reference.samples.t, reference.duration
    keeps = np.flatnonzero(inflated.points_free(reference.samples.position))
    if not keeps.size:
        return 0.0, duration
    return (float(t[keeps[0]]) if start_leg else 0.0,
            float(t[keeps[-1]]) if goal_leg else duration)
