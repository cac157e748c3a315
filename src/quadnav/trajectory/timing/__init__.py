"""Segment times: a trapezoidal speed profile per segment and times optimised for a cost
(:mod:`.segment_times`), the fastest speed along a curve (:mod:`.speed_profile`), and
near time-optimal retiming within speed and acceleration limits (:mod:`.retime`)."""
