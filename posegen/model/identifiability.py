"""Base parameters by QR with column pivoting of the stacked regressor.

The regressor is the Jacobian of the measurements with respect to every parameter,
stacked over many postures, its rows scaled by the measurement noise and its columns by
the parameters' physical sizes (so pivoting does not favour a unit). Columns are chosen
in priority blocks: the table planes first (they differ by session and must be kept),
then everything else, each block pivoted in the orthogonal complement of what was
already chosen. The dependent parameters are set to zero deviation; the grouping
matrix says which combination of them each base parameter absorbs.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from posegen.errors import InfeasibleError
from posegen.robot import FloatArray, Indices

RANK_TOLERANCE = 1e-4  # |R_ii| below this times |R_00| counts as zero (TALOS gap: 9e-3 down to 1e-14)


@dataclass(frozen=True)
class BaseParameters:
    """Identifiable combinations of a model's parameters."""

    columns: tuple[int, ...]  # model parameter indices kept as base parameters
    dependent: tuple[int, ...]  # the others (held at their nominal value)
    grouping: FloatArray  # (nb, nd): scaled base_i absorbs sum_j grouping[i, j] * scaled dependent_j
    diagonal: FloatArray  # (nb,) |R_ii| of the chosen columns (scaled units), decreasing per block

    @property
    def size(self) -> int:
        """Number of base parameters."""
        return len(self.columns)


def _pivoted_block(matrix: FloatArray, scale_ref: float) -> tuple[list[int], FloatArray]:
    if matrix.shape[1] == 0:
        return [], np.zeros(0)
    _, r, perm = scipy.linalg.qr(matrix, mode="economic", pivoting=True)
    diag = np.abs(np.diag(r))
    ref = max(scale_ref, diag[0] if len(diag) else 0.0)
    rank = int(np.sum(diag > RANK_TOLERANCE * ref))
    return [int(p) for p in perm[:rank]], diag[:rank]


def base_parameters(regressor: FloatArray, column_scale: FloatArray, priority: Sequence[Indices]) -> BaseParameters:
    """Find the base parameters of a stacked regressor.

    Args:
        regressor: (m, p) Jacobian of the (noise-scaled) measurements.
        column_scale: (p,) physical size of each parameter (m or rad).
        priority: Blocks of column indices, most preferred first; every column must be
            in exactly one block.

    Raises:
        InfeasibleError: The regressor has no identifiable parameter.

    """
    scaled = regressor * column_scale[None, :]
    chosen: list[int] = []
    diagonals: list[FloatArray] = []
    ref = 0.0
    basis = np.zeros((scaled.shape[0], 0))
    for block in priority:
        cols = np.array(block, dtype=int)
        part = scaled[:, cols]
        if basis.shape[1]:
            part = part - basis @ (basis.T @ part)
        picked, diag = _pivoted_block(part, ref)
        if len(diag):
            ref = max(ref, float(diag[0]))
        chosen.extend(int(cols[i]) for i in picked)
        diagonals.append(diag)
        basis, _ = np.linalg.qr(scaled[:, chosen]) if chosen else (basis, None)
    if not chosen:
        raise InfeasibleError("no identifiable parameter: the regressor is zero (too few or identical postures?)")
    dependent = [c for c in range(scaled.shape[1]) if c not in set(chosen)]
    base = scaled[:, chosen]
    grouping = np.zeros((len(chosen), 0))
    if dependent:
        grouping = np.asarray(np.linalg.lstsq(base, scaled[:, dependent], rcond=None)[0], dtype=float)
    return BaseParameters(
        columns=tuple(chosen),
        dependent=tuple(dependent),
        grouping=grouping,
        diagonal=np.concatenate(diagonals),
    )


def observability_o1(regressor: FloatArray, n_postures: int) -> float:
    """O1 index: (prod of singular values)^(1/nb) / sqrt(n_postures), via QR (no slogdet).

    Args:
        regressor: (m, nb) base regressor, full column rank expected.
        n_postures: Number of postures stacked.

    Returns:
        O1, or 0.0 when the regressor is rank deficient.

    """
    m, nb = regressor.shape
    if m < nb:
        return 0.0
    r = np.linalg.qr(regressor, mode="r")
    diag = np.abs(np.diag(r))
    if np.any(diag <= RANK_TOLERANCE * max(diag.max(), 1e-300)):
        return 0.0
    return float(np.exp(np.mean(np.log(diag))) / np.sqrt(n_postures))
