"""The information matrix and the Frank-Wolfe line search, against plain computations."""

import numpy as np
import pytest

from posegen.model import information
from posegen.select.optimal_weights import _step_length


def test_information_is_the_weighted_sum_of_the_postures_information():
    rng = np.random.default_rng(4)
    regressors = rng.standard_normal((50, 3, 12))  # (n, 3, nb)
    weights = rng.dirichlet(np.ones(50))
    weights[::7] = 0.0  # postures outside the support
    plain = sum(w * a.T @ a for w, a in zip(weights, regressors, strict=True))
    matrix = information(regressors, weights)
    assert matrix == pytest.approx(plain, rel=1e-12, abs=1e-14)
    assert np.array_equal(matrix, matrix.T)  # mirrored exactly


@pytest.mark.parametrize(("low", "high"), [(0.0, 1e12), (-0.02, 0.0), (0.0, 0.05)])
def test_step_length_maximises_the_log_det_along_the_segment(low, high):
    """f(t) = sum log(1 + t lambda) - nb log(1 + t): the returned t beats a dense grid of the interval.

    (An away step's interval keeps every ``1 + t lambda`` positive: ``-w_j lambda <= 1``.)
    """
    eigen, nb = np.array([40.0, 12.0, 0.5]), 12

    def f(t):
        return float(np.sum(np.log1p(t * eigen)) - nb * np.log1p(t))

    t = _step_length(eigen, nb, low, high)
    assert low <= t <= high
    grid = np.linspace(low, min(high, 50.0), 20001)
    if high > 50.0:
        grid = np.concatenate([grid, np.geomspace(50.0, high, 200)])
    assert f(t) >= max(f(s) for s in grid) - 1e-12
