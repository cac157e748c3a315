"""A flight record as CSV text."""

from __future__ import annotations

import numpy as np

from quadnav.control.contract import REFERENCE_POSITION
from quadnav.sim.flight import Flight
from quadnav.trajectory.references.export import csv_table

#: Header of :func:`flight_csv`: time s, position m, velocity m/s, attitude quaternion,
#: motor commands in [0, 1], and the reference position m.
FLIGHT_HEADER = "t,x,y,z,vx,vy,vz,qw,qx,qy,qz,u1,u2,u3,u4,x_ref,y_ref,z_ref"


def flight_csv(flight: Flight) -> str:
    """One row per recorded sample (the record rate, then the final state), columns
    :data:`FLIGHT_HEADER`; motors numbered as :mod:`quadnav.vehicle.rotors`."""
    return csv_table(np.column_stack([flight.t, flight.position, flight.velocity,
                                      flight.attitude, flight.commands,
                                      flight.reference[:, REFERENCE_POSITION]]),
                     FLIGHT_HEADER)
