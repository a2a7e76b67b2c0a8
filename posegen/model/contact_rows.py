"""Which of a contact's three measurement rows are real.

Every contact keeps the (height, roll, pitch) layout, (n, 3) residuals and (n, 3, p)
Jacobians, so the design formulas (log det, rank-3 updates, Kiefer-Wolfowitz) hold for
any mix of kinds. Each kind says which rows it measures (``ContactKind.rows``): a flush
contact all three, a point contact only the height, its roll and pitch rows zero,
residual and Jacobian alike. Whatever counts
measurements (equations against unknowns, degrees of freedom of a noise estimate or an
outlier test, the mean of a cross-validation score) counts the real rows, given here.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from posegen.robot import ContactKind, FloatArray


def row_mask(kinds: Sequence[ContactKind]) -> NDArray[np.bool_]:
    """Which of each contact's (height, roll, pitch) rows are measured. Shape (n, 3)."""
    return np.array([k.rows for k in kinds], dtype=bool).reshape(len(kinds), 3)


def row_counts(kinds: Sequence[ContactKind]) -> NDArray[np.int_]:
    """Number of real rows of each contact (3 flush, 1 point). Shape (n,)."""
    return np.array([sum(k.rows) for k in kinds], dtype=int)


def masked(residuals: FloatArray, kinds: Sequence[ContactKind]) -> FloatArray:
    """Residuals (n, 3) with the rows a contact does not measure set to NaN (for nan-aware statistics)."""
    return np.where(row_mask(kinds), residuals, np.nan)
