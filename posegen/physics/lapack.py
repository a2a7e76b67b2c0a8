"""Small dense solves on the control loop's hot path, called through LAPACK directly.

The controllers solve a few systems of 2 to 12 unknowns every control period (250 Hz,
tens of thousands of periods a run). ``np.linalg.solve`` spends about 5 us a call on its
checks and wrapping, several times the solve itself; the LAPACK routines it calls
(``dgesv``, i.e. ``dgetrf`` then ``dgetrs``), called through SciPy, give the same numbers
in about a quarter of the time, and a matrix that does not change is factored once
(:class:`Factored`).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg.lapack import dgesv, dgetrf, dgetrs

from posegen.robot import FloatArray


def solve(matrix: FloatArray, vector: FloatArray) -> FloatArray:
    """``x`` (n,) with ``matrix @ x = vector``, ``matrix`` (n, n) (as ``np.linalg.solve``, the same numbers).

    Raises:
        numpy.linalg.LinAlgError: ``matrix`` is singular (as ``np.linalg.solve``).

    Example:
        >>> solve(np.array([[2.0, 0.0], [0.0, 4.0]]), np.array([1.0, 1.0]))
        array([0.5 , 0.25])

    """
    _, _, x, info = dgesv(matrix, vector)
    if info != 0:
        raise np.linalg.LinAlgError("Singular matrix")
    return np.asarray(x)


class Factored:
    """A square matrix factored once (LU), then solved against many vectors.

    Example:
        >>> Factored(np.diag([2.0, 4.0])).solve(np.array([1.0, 1.0]))
        array([0.5 , 0.25])

    """

    def __init__(self, matrix: FloatArray) -> None:
        """Factor ``matrix`` (n, n) (a copy: later changes to it are not seen).

        Raises:
            numpy.linalg.LinAlgError: ``matrix`` is singular.

        """
        lu, pivots, info = dgetrf(np.array(matrix, dtype=float))
        if info != 0:
            raise np.linalg.LinAlgError("Singular matrix")
        self._lu, self._pivots = lu, pivots

    def solve(self, vector: FloatArray) -> FloatArray:
        """``x`` (n,) with ``matrix @ x = vector`` (as ``np.linalg.solve(matrix, vector)``, the same numbers)."""
        x, _ = dgetrs(self._lu, self._pivots, vector)
        return np.asarray(x)
