"""Lines of a flight's summary that ``fly``, ``track`` and ``kino --fly`` print alike,
from a ``metrics.json`` dictionary (lengths in m, printed in cm where they are errors)."""

from __future__ import annotations

import sys

import numpy as np

from quadnav.arrays import FloatArray
from quadnav.world.placement import format_point

#: What ``--strict`` adds to the failure line when a flight kept less margin than asked.
STRICT_FAILURE = "it kept less margin than asked (--strict)"


def tracking_errors(m: dict) -> str:
    """``tracking error RMS a cm, max b cm; final error c cm``."""
    return (f"tracking error RMS {100 * m['rms_tracking_error_m']:.2f} cm, max "
            f"{100 * m['max_tracking_error_m']:.2f} cm; final error "
            f"{100 * m['final_error_m']:.2f} cm")


def clearance_text(m: dict) -> str:
    """``min clearance d m``, or ``min clearance none (no blocks)``."""
    clearance = m["min_clearance_m"]
    return "min clearance " + ("none (no blocks)" if clearance is None else
                               f"{clearance:.3f} m")


def simulation_time(m: dict) -> str:
    """``loading the loop a s, simulation b s (cx real time)``: the one-off loading apart
    from the loop, whose time alone the real-time factor divides."""
    return (f"loading the loop {m['sim_load_time_s']:.2f} s, simulation "
            f"{m['sim_wall_time_s']:.2f} s ({m['real_time_factor']:.0f}x real time)")


def margin_shortfall(m: dict, t: FloatArray, positions: FloatArray) -> str | None:
    """``the flight kept only a m of the b m margin asked off the legs (c m short), least
    at t = d s near (x, y, z)`` when the flight of ``m`` kept less than asked
    (``margin_shortfall_m`` above 0, however little), else None. ``t`` (N,) s and
    ``positions`` (N, 3) m are the flight's records, where the place is read."""
    short = m.get("margin_shortfall_m")
    if not short:
        return None
    time = m["flight_margin_time_s"]
    place = positions[min(int(np.searchsorted(t, time)), len(t) - 1)]
    return (f"the flight kept only {m['flight_margin_m']:.3f} m of the {m['margin_m']:g} m "
            f"margin asked off the legs ({short:.3g} m short), least at t = {time:.2f} s "
            f"near {format_point(place, '.2f')}")


def warn_margin_shortfall(m: dict, t: FloatArray, positions: FloatArray) -> bool:
    """Print :func:`margin_shortfall` as a warning line on stderr if there is one; returns
    whether there was."""
    line = margin_shortfall(m, t, positions)
    if line is not None:
        print(f"quadnav: warning: {line}", file=sys.stderr)
    return line is not None


def flight_failed(failure: str | None, short: bool, strict: bool) -> bool:
    """Whether a flight failed: it did not succeed (``failure`` says why; None when it
    succeeded), or, with ``strict``, it kept less margin than asked (``short``). Prints the
    one ``quadnav: flight failed: ...`` line on stderr when it did."""
    why = failure if failure is not None else STRICT_FAILURE if strict and short else None
    if why is not None:
        print(f"quadnav: flight failed: {why}", file=sys.stderr)
    return why is not None
