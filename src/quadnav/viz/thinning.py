"""Thinning what is drawn: a tree of 100,000 edges reads no better than one of 20,000."""

from __future__ import annotations

import numpy as np


def evenly_spread(items: np.ndarray, limit: int) -> np.ndarray:
    """At most ``limit`` rows of ``items`` (N, ...), evenly spread from the first to the
    last and in their order; all of them when there are no more than ``limit``."""
    return items[np.linspace(0, len(items) - 1, min(len(items), limit)).astype(int)]
