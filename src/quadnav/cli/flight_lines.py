"""Lines of a flight's summary that ``fly``, ``track`` and ``kino --fly`` print alike,
from a ``metrics.json`` dictionary (lengths in m, printed in cm where they are errors)."""

from __future__ import annotations


def tracking_errors(m: dict) -> str:
    """``tracking error RMS a cm, max b cm; final error c cm``."""
    return (f"tracking error RMS {100 * m['rms_tracking_error_m']:.2f} cm, max "
            f"{100 * m['max_tracking_error_m']:.2f} cm; final error "
            f"{100 * m['final_error_m']:.2f} cm")


def min_clearance(m: dict) -> str:
    """``min clearance d m``, or ``min clearance none (no blocks)``."""
    clearance = m["min_clearance_m"]
    return "min clearance " + ("none (no blocks)" if clearance is None else
                               f"{clearance:.3f} m")
