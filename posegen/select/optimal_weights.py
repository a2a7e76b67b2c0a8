"""Continuous D-optimal weights: maximise log det(sum_i w_i I_i) on the simplex.

Frank-Wolfe with away steps (Wolfe 1970; Todd and Yildirim 2007 for this problem) and
exact line searches. With M(w) = sum_i w_i I_i and d_i = trace(M^-1 I_i), w is optimal
iff max_i d_i = nb (Kiefer-Wolfowitz); the gap max_i d_i / nb - 1 certifies any w: its
D-efficiency is at least nb / max_i d_i.

Every I_i has rank 3 (three measurements per posture), so a step towards or away from a
posture is a rank-3 update: M^-1 and all d_i are updated in O(n nb) per step, and
recomputed exactly now and then against drift.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.optimize

from posegen.model import Design, information
from posegen.robot import FloatArray

REFRESH_EVERY = 50  # exact recomputation of M^-1 and d every this many steps
WARM_START = 30  # multiplicative-algorithm steps before Frank-Wolfe (each a full pass)
ACTIVE_PER_PARAMETER = 4  # the first active set: this many candidates per base parameter (the support holds
# about 3 per parameter: 363 postures for 114 on 20 000); a quarter of the pool instead was 5x slower there


@dataclass(frozen=True)
class OptimalWeights:
    """Continuous design and its optimality certificate."""

    weights: FloatArray  # (n,) on the simplex
    gap: float  # max_i d_i / nb - 1 (0 at the optimum)
    iterations: int

    @property
    def efficiency_bound(self) -> float:
        """Lower bound of the D-efficiency: nb / max d_i = 1 / (1 + gap)."""
        return 1.0 / (1.0 + self.gap)

    @property
    def o1_ratio_bound(self) -> float:
        """Lower bound of O1(w) / O1*: sqrt of the efficiency bound."""
        return float(np.sqrt(self.efficiency_bound))


def _variances(regressors: FloatArray, inverse: FloatArray) -> FloatArray:
    """d_i = trace(M^-1 A_i^T A_i) for every posture. Shape (n,)."""
    n, _, nb = regressors.shape
    flat = regressors.reshape(-1, nb)
    return np.asarray(((flat @ inverse) * flat).sum(axis=1).reshape(n, 3).sum(axis=1))


def _step_length(eigen: FloatArray, nb: int, low: float, high: float) -> float:
    """Maximise f(t) = sum log(1 + t lambda_k) - nb log(1 + t) over t in [low, high].

    The slope is summed over the (3,) eigenvalues in plain floats: the same operations, in
    the same order, as numpy's sum of so few, without an array per evaluation.
    """
    values = [float(v) for v in eigen]

    def slope(t: float) -> float:
        total = 0.0
        for value in values:
            total += value / (1.0 + t * value)
        return total - nb / (1.0 + t)

    if slope(low) <= 0:
        return low
    if slope(high) >= 0:
        return high
    return float(scipy.optimize.brentq(slope, low, high, xtol=1e-14, rtol=1e-12))


def d_optimal_weights(design: Design, tolerance: float = 1e-4, max_iterations: int = 20000) -> OptimalWeights:
    """Frank-Wolfe with away steps until the Kiefer-Wolfowitz gap is below ``tolerance``.

    After a warm start, the steps run on an active set (the candidates with the largest
    variances); the gap is always certified on the whole pool, and candidates that
    violate it join the active set until it holds.

    Args:
        design: Candidate postures.
        tolerance: Target gap max_i d_i / nb - 1.
        max_iterations: Cap on steps.

    """
    a = design.regressors
    n, nb = design.size, design.n_params
    weights = np.full(n, 1.0 / n)
    for _ in range(WARM_START):  # w_i <- w_i d_i / nb (Titterington): fast early progress
        weights = weights * _variances(a, np.linalg.inv(information(a, weights))) / nb
        weights /= weights.sum()
    d = _variances(a, np.linalg.inv(information(a, weights)))
    active = np.sort(np.argsort(-d)[: min(n, ACTIVE_PER_PARAMETER * nb)])
    weights[np.setdiff1d(np.arange(n), active)] = 0.0
    weights /= weights.sum()
    iterations = 0
    while True:
        sub, steps = _frank_wolfe(a[active], weights[active], tolerance, max_iterations - iterations)
        iterations += steps
        weights[:] = 0.0
        weights[active] = sub
        d = _variances(a, np.linalg.inv(information(a, weights)))
        violators = np.setdiff1d(np.flatnonzero(d / nb - 1.0 > tolerance), active)
        if len(violators) == 0 or iterations >= max_iterations:
            break
        active = np.union1d(active, violators)
    gap = float(np.max(d) / nb - 1.0)
    return OptimalWeights(weights=weights, gap=max(gap, 0.0), iterations=iterations)


def _frank_wolfe(a: FloatArray, weights: FloatArray, tolerance: float, max_iterations: int) -> tuple[FloatArray, int]:
    """Frank-Wolfe with away steps on candidates ``a`` (n, 3, nb) from ``weights``."""
    n, _, nb = a.shape
    weights = weights.copy()
    flat = a.reshape(-1, nb)
    inverse = np.linalg.inv(information(a, weights))
    d = _variances(a, inverse)
    iterations = 0
    while iterations < max_iterations:
        iterations += 1
        if iterations % REFRESH_EVERY == 0:
            inverse = np.linalg.inv(information(a, weights))
            d = _variances(a, inverse)
        toward = int(np.argmax(d))
        if d[toward] / nb - 1.0 <= tolerance:
            break
        support = np.flatnonzero(weights > 0)
        away = int(support[np.argmin(d[support])])
        g_toward = d[toward] - nb
        g_away = nb - d[away]
        j = toward if g_toward >= g_away or weights[away] >= 1.0 else away
        g = inverse @ a[j].T  # (nb, 3)
        eigen = np.linalg.eigvalsh(a[j] @ g)  # of A_j M^-1 A_j^T
        if j == toward:
            t = _step_length(eigen, nb, 0.0, 1e12)
        else:  # w <- (1 + s) w - s e_j with s <= w_j / (1 - w_j), i.e. t = -s / (1 + s) >= -w_j
            t = _step_length(eigen, nb, -weights[away], 0.0)
        alpha = t / (1.0 + t)  # negative for an away step
        if abs(alpha) < 1e-16:
            break
        weights *= 1.0 - alpha
        weights[j] += alpha
        weights[weights < 1e-14] = 0.0
        # M_new = (1 - alpha)(M + t I_j): rank-3 Woodbury update of M^-1 and of every d_i
        s_matrix = np.linalg.inv(np.eye(3) / t + a[j] @ g)
        c = (flat @ g).reshape(n, 3, 3)  # A_i M^-1 A_j^T
        d = (1.0 + t) * (d - ((c @ s_matrix) * c).sum(axis=(1, 2)))
        inverse = (1.0 + t) * (inverse - g @ s_matrix @ g.T)
    return weights / weights.sum(), iterations
