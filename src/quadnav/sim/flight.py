"""What a simulated flight returns: :class:`Flight`."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.control.contract import REFERENCE_POSITION
from quadnav.sim.excursion import Excursion
from quadnav.vehicle.dynamics import ATTITUDE, POSITION, VELOCITY


class Ending(Enum):
    """Why a flight stopped."""

    COMPLETED = "completed"  # the trajectory's end plus the settling time
    COLLISION = "collision"  # the body box touched a real block
    LEFT_BOUNDARY = "left boundary"  # the centre left the map's boundary
    DIVERGED = "diverged"  # a non-finite state or the vehicle upside down
    FLOOR = "hit the floor"  # met the floor too fast, or where the reference is above it


@dataclass(frozen=True, eq=False)
class Flight:
    """A flight record, sampled at the record rate, plus the final state.

    Attributes:
        t: (N,) times, s, from the start of the trajectory.
        states: (N, 17) vehicle states (layout of :mod:`quadnav.vehicle.dynamics`).
        commands: (N, 4) motor commands in [0, 1] held from each sample on.
        reference: (N, 11) reference at each sample: position m, velocity m/s,
            acceleration m/s^2, yaw rad, yaw rate rad/s.
        goal: (3,) where the trajectory ends, m.
        ending: why it stopped.
        contact_time: when it collided, left the boundary, diverged or hit the floor, s
            (else None).
        contact_block: row of the real block touched, for a collision (else None).
        rms_tracking_error: root mean square of the position error over every control
            step, m.
        max_tracking_error: largest position error at any control step, m.
        max_velocity_error: largest velocity error at any control step, m/s.
        mixer_saturation: fraction of control steps at which the mixer had to change
            the wrench.
        wall_time: seconds the closed loop ran, from its first control step to its last
            (with the progress updates between its chunks): what real-time factors divide.
        load_time: seconds before the loop: the reference sampled, the disturbances drawn
            and the compiled loop loaded (numba's dispatch, and on a process's first flight
            a load from numba's cache or a compile), a one-off cost apart from
            ``wall_time``.
        rotor_energy: the rotors' aerodynamic work over the flight, J: the drag torque
            times the speed of each rotor, ``k_m w^3``, summed over the four and integrated
            over the recorded samples (trapezoids); a measure to compare flights by, not a
            battery's drain (motor and electronics losses are left out).
        floor_speed: the fastest the centre met the floor, m/s (the speed the floor stopped,
            checked at every physics step; None if it never met it): a landing or the rest
            before a take-off, or for :attr:`Ending.FLOOR` the crash
            (:func:`~quadnav.sim.loop.touchdown`).
        body_outside: how far and how long the body box left the map's boundary after
            the start (:func:`~quadnav.sim.excursion.body_excursion`; none in open space).
        info: the settings and vehicle used, JSON-ready.
    """

    t: FloatArray
    states: FloatArray
    commands: FloatArray
    reference: FloatArray
    goal: FloatArray
    ending: Ending
    contact_time: float | None
    contact_block: int | None
    rms_tracking_error: float
    max_tracking_error: float
    max_velocity_error: float
    mixer_saturation: float
    wall_time: float
    load_time: float
    rotor_energy: float
    floor_speed: float | None = None
    body_outside: Excursion = field(default_factory=Excursion)
    info: dict = field(default_factory=dict)

    @property
    def position(self) -> FloatArray:
        """(N, 3) positions, m."""
        return self.states[:, POSITION]

    @property
    def velocity(self) -> FloatArray:
        """(N, 3) velocities, m/s."""
        return self.states[:, VELOCITY]

    @property
    def attitude(self) -> FloatArray:
        """(N, 4) attitude quaternions ``(w, x, y, z)``."""
        return self.states[:, ATTITUDE]

    @property
    def duration(self) -> float:
        """Flight time, s."""
        return float(self.t[-1])

    @property
    def final_error(self) -> float:
        """Distance from the final position to the goal, m."""
        return float(np.linalg.norm(self.position[-1] - self.goal))

    @property
    def tracking_error(self) -> FloatArray:
        """(N,) position error at each sample, m."""
        return np.linalg.norm(self.position - self.reference[:, REFERENCE_POSITION], axis=1)
