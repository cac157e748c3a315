"""The Tello bridge: a trajectory as a checked flight plan for a Tello (SDK moves or
curves, geofence, rooms of the legs, ``rc`` mode's lost-link bound), the link to the
drone and its log, the flight itself (safe stops, landing, dead reckoning), and the
flight as a run folder with its figure.
"""
