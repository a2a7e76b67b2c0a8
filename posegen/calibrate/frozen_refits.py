"""Refits with a frozen Jacobian (the chord method): each fold of a cross-validation from the fit on all rows.

A fold's training rows are nearly all rows: its fit is close to the fit on all of them,
whose Jacobian (:func:`posegen.calibrate.estimation.frozen_jacobian`) serves every fold's
Gauss-Newton steps. One factorisation per fold, then one residual evaluation per step,
for every fold at once.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.linalg

from posegen.calibrate.estimation import Noise
from posegen.model import CalibrationModel, Observations, Spec
from posegen.robot import FloatArray


def refit_frozen(
    model: CalibrationModel,
    observations: Observations,
    spec: Spec,
    noise: Noise,
    start: FloatArray,
    jacobian: tuple[FloatArray, FloatArray],
    iterations: int,
) -> FloatArray:
    """Deviations (nx,) of the MAP fit by Gauss-Newton steps with a frozen Jacobian (chord method).

    Each step uses the true residuals of ``observations`` and the Jacobian of another fit
    close by (the fit on all rows, for a fold of it): one factorisation, then one
    residual evaluation per step. ``jacobian`` holds these postures' rows and the prior rows.
    """
    every = [range(len(observations))]
    return refit_frozen_folds(model, observations, spec, noise, start, jacobian, every, iterations)[0]


def refit_frozen_folds(
    model: CalibrationModel,
    observations: Observations,
    spec: Spec,
    noise: Noise,
    start: FloatArray,
    jacobian: tuple[FloatArray, FloatArray],
    folds: Sequence[Sequence[int]],
    iterations: int,
) -> FloatArray:
    """:func:`refit_frozen` of F folds at once, each on its own rows of ``observations``. Shape (F, nx).

    Every fold takes its steps from ``start`` with its rows of the frozen Jacobian
    ``jacobian`` (of all the observations' postures, and the prior rows); the residuals of
    every fold's parameters are evaluated together (:meth:`CalibrationModel.evaluate_batch`),
    the same numbers as one fold at a time.

    Example:
        >>> deltas = refit_frozen_folds(model, observations, spec, noise, x, jacobian, [f.train for f in folds], 3)

    """
    per_posture, prior_rows = jacobian
    f = per_posture.shape[2]
    free = np.array(spec.free, dtype=int)
    fixed = model.delta_of(start)
    sd = spec.prior_sd[free]
    prior = np.isfinite(sd)
    sigma = np.array(noise.contact + noise.floor)[: 9 if spec.floor else 3]
    rows = [np.asarray(list(fold), dtype=int) for fold in folds]
    if not rows:
        return np.zeros((0, model.size))
    matrices, factors = [], []
    for mine in rows:
        # in the order of the residual: every contact row, then every floor row, then the prior
        matrix = np.vstack([per_posture[mine, :3].reshape(-1, f), per_posture[mine, 3:].reshape(-1, f), prior_rows])
        matrices.append(matrix)
        factors.append(scipy.linalg.cho_factor(matrix.T @ matrix))
    deltas = np.tile(fixed, (len(rows), 1))
    for _ in range(iterations):
        contact, floor = model.evaluate_batch(model.nominal() + deltas @ model.basis.T, observations, spec.floor)
        whitened = np.concatenate([contact, floor], axis=2) / sigma  # (F, n, 3 or 9)
        for k, mine in enumerate(rows):
            values = deltas[k, free]
            residual = np.concatenate(
                [whitened[k, mine, :3].ravel(), whitened[k, mine, 3:].ravel(), values[prior] / sd[prior]]
            )
            deltas[k, free] = values - scipy.linalg.cho_solve(factors[k], matrices[k].T @ residual)
    return deltas
