"""Array types and number checks every layer shares, defined once at the bottom (below :mod:`posegen.io`)."""

from __future__ import annotations

import math
from typing import Any, TypeGuard

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.floating[Any]]  # any shape: the shape is given where it is used, in a comment


def is_finite_number(value: object) -> TypeGuard[int | float]:
    """Whether ``value`` is an int or float (not a bool) and finite (an int beyond a float's range is not).

    Example:
        >>> is_finite_number(0.5), is_finite_number(float("nan")), is_finite_number(True), is_finite_number(10**400)
        (True, False, False, False)

    """
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:  # an int too large for a float (YAML reads 400 digits as one)
        return False


__all__ = ["FloatArray", "is_finite_number"]
