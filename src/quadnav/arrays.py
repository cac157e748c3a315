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


def frozen(values: object, dtype: type) -> np.ndarray:
    """``values`` as a read-only array of ``dtype``, for the fields of frozen values: an
    array that already is one — read-only, and so is every array it is a view of (a field
    of another frozen value) — is shared; anything else is copied first, so that no caller
    can change it afterwards."""
    if isinstance(values, np.ndarray) and values.dtype == dtype:
        array = values
        while isinstance(array, np.ndarray) and not array.flags.writeable:
            if array.base is None:
                return values
            array = array.base
    return read_only(np.array(values, dtype=dtype))
