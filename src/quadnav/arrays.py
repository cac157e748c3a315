"""Array types and helpers every stage shares."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

#: A float64 array; its shape is stated where it is used, e.g. (N, 3) points in metres.
FloatArray = NDArray[np.float64]


def read_only(array: np.ndarray) -> np.ndarray:
    """``array`` made read-only (in place) and returned, for the fields of frozen values."""
    array.flags.writeable = False
    return array
