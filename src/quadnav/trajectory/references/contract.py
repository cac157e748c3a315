"""What the simulation flies: the :class:`Reference` contract, and sampling one.

A reference is anything that gives the desired position, velocity, acceleration and yaw
at any time: a :class:`~quadnav.trajectory.model.Trajectory` through waypoints, a built-in
shape (:mod:`quadnav.trajectory.references.builtin`: a circle is flown as a circle, not as a
polynomial fitted to it) or samples read from a file (:mod:`quadnav.trajectory.references.sampled`).
:func:`quadnav.sim.simulate` and the run folder use nothing else of it.

Units and shapes: times in seconds from the start, a scalar or an (N,) array; positions m,
velocities m/s, accelerations m/s^2 in the world frame (z up), (3,) for a scalar time and
(N, 3) for (N,) times; yaw in rad, a scalar or (N,). Before the start and after the end
(``duration``) a reference holds still: the first or last position, every derivative zero
and the first or last yaw.

A reference may also have ``yaw_rate(t)`` (rad/s, the shape of ``yaw``): the closed loop
then flies that yaw rate (a plain-Python trajectory's ``yaw_dot``,
:mod:`quadnav.trajectory.references.plain`) instead of the finite difference of the yaw.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from quadnav.arrays import FloatArray
from quadnav.limits import MAX_SAMPLES, check_count

#: A last sample closer than this share of the interval to the end is moved to the end
#: rather than followed by it (two times that close would print alike).
END_SNAP = 1e-6


@dataclass(frozen=True)
class Samples:
    """A reference sampled at times ``t`` (N,) s: position, velocity, acceleration (N, 3)
    in m, m/s, m/s^2 and yaw (N,) rad."""

    t: FloatArray
    position: FloatArray
    velocity: FloatArray
    acceleration: FloatArray
    yaw: FloatArray


@runtime_checkable
class Reference(Protocol):
    """A desired motion over time (see the module docstring for units, shapes and what
    holds outside ``[0, duration]``).

    Any class with these members is a Reference (no need to subclass it); :class:`Sampling`
    gives a class :meth:`sample`.
    """

    @property
    def duration(self) -> float:
        """How long the motion lasts, s (> 0)."""
        ...

    def position(self, t: ArrayLike) -> FloatArray:
        """Position, m, at ``t`` s: scalar -> (3,), (N,) -> (N, 3)."""
        ...

    def velocity(self, t: ArrayLike) -> FloatArray:
        """Velocity, m/s, at ``t`` s: scalar -> (3,), (N,) -> (N, 3)."""
        ...

    def acceleration(self, t: ArrayLike) -> FloatArray:
        """Acceleration, m/s^2, at ``t`` s: scalar -> (3,), (N,) -> (N, 3)."""
        ...

    def yaw(self, t: ArrayLike) -> FloatArray:
        """Yaw, rad, at ``t`` s: scalar -> scalar, (N,) -> (N,)."""
        ...

    def sample(self, dt: float) -> Samples:
        """Samples every ``dt`` s from 0 to the end, the end included, as
        :func:`sample_every`."""
        ...


class Sampling:
    """Gives a reference class :meth:`Reference.sample`, by :func:`sample_every`."""

    def sample(self, dt: float) -> Samples:
        """Samples every ``dt`` s from 0 to the end, the end included.

        Raises:
            QuadnavError: more than :data:`~quadnav.limits.MAX_SAMPLES` samples.
        """
        return sample_every(self, dt)


def samples_at(reference: Reference, t: ArrayLike) -> Samples:
    """``reference`` at the times ``t`` (N,) s."""
    times = np.asarray(t, dtype=np.float64).reshape(-1)
    yaw = np.broadcast_to(reference.yaw(times), times.shape).astype(np.float64)
    return Samples(times, reference.position(times), reference.velocity(times),
                   reference.acceleration(times), yaw)


def _check_interval(duration: float, dt: float) -> None:
    """ValueError for a ``dt`` not > 0; QuadnavError for more than
    :data:`~quadnav.limits.MAX_SAMPLES` samples of a ``duration`` s reference."""
    if not dt > 0:
        raise ValueError(f"dt must be > 0 s, got {dt}")
    check_count(duration / dt + 1, MAX_SAMPLES, f"a {duration:.6g} s reference sampled every "
                f"{dt:g} s gives samples", "sample less often (--dt) or raise the speed")


def sample_times(duration: float, dt: float) -> FloatArray:
    """(N,) times every ``dt`` s from 0, and the end ``duration`` s: the last multiple of
    ``dt`` is followed by the end, or moved to it when it lies within :data:`END_SNAP` x
    ``dt`` of it.

    Raises:
        ValueError: ``dt`` not > 0.
        QuadnavError: more than :data:`~quadnav.limits.MAX_SAMPLES` samples.
    """
    _check_interval(duration, dt)
    t = np.arange(int(np.floor(duration / dt + 1e-9)) + 1) * dt
    if duration - t[-1] > END_SNAP * dt:
        return np.append(t, duration)
    if len(t) > 1:
        t[-1] = duration
    return t


def sample_every(reference: Reference, dt: float) -> Samples:
    """``reference`` sampled at :func:`sample_times` of its duration."""
    return samples_at(reference, sample_times(reference.duration, dt))


def grid_times(duration: float, dt: float) -> FloatArray:
    """(N,) times ``k dt`` for k = 0 .. ceil(duration / dt): exactly uniform, the last at
    or after the end (where a reference holds still), or within 1e-9 ``dt`` before it; for
    a file with no times, such as the course's MP.csv.

    Raises:
        ValueError: ``dt`` not > 0.
        QuadnavError: more than :data:`~quadnav.limits.MAX_SAMPLES` samples.
    """
    _check_interval(duration, dt)
    return np.arange(int(np.ceil(duration / dt - 1e-9)) + 1) * dt
