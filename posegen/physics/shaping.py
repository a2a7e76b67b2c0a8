"""How the controllers shape their signals: a deadband, a saturation, a rate stopped at its bound.

The controllers run at every control period on arrays of 1 to 6 values, where
``np.clip`` costs several microseconds a call: these are written with the ufuncs
``np.minimum`` and ``np.maximum`` (the same numbers, NaN and signed zeros included).
"""

from __future__ import annotations

import numpy as np

from posegen.robot import FloatArray


def beyond(values: FloatArray | float, band: FloatArray | float) -> FloatArray:
    """Each value less its band toward zero; zero within the band (a deadband).

    Example:
        >>> beyond(np.array([0.3, -0.05, -0.2]), 0.1)
        array([ 0.2, -0. , -0.1])

    """
    return np.asarray(np.sign(values) * np.maximum(np.abs(values) - band, 0.0))


def clamp(values: FloatArray, lower: FloatArray | float, upper: FloatArray | float) -> FloatArray:
    """``values`` held within ``[lower, upper]`` (as ``np.clip``).

    Example:
        >>> clamp(np.array([-2.0, 0.5, 3.0]), -1.0, 1.0)
        array([-1. ,  0.5,  1. ])

    """
    return np.asarray(np.minimum(np.maximum(values, lower), upper))


def saturate(values: FloatArray, limit: FloatArray | float) -> FloatArray:
    """``values`` held within ``[-limit, limit]``.

    Example:
        >>> saturate(np.array([0.03, -0.01]), 0.02)
        array([ 0.02, -0.01])

    """
    return clamp(values, -limit, limit)


def bounded_rate(rate: FloatArray, limit: float, value: FloatArray, bound: float) -> FloatArray:
    """``rate`` held within ``[-limit, limit]``, and zero where it would carry ``value`` past ``[-bound, bound]``.

    A value at its bound may still move back (the rates that integrate an angle or an
    offset kept within its bound).

    Example:
        >>> bounded_rate(np.array([0.3, 0.3, -0.1]), 0.2, np.array([0.0, 0.05, 0.05]), 0.05)
        array([ 0.2,  0. , -0.1])

    """
    saturated = saturate(rate, limit)
    blocked = np.abs(value) >= bound
    return np.asarray(np.where(blocked & (np.sign(saturated) == np.sign(value)), 0.0, saturated))
