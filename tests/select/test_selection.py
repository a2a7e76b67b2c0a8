"""Design, optimal weights, exact subsets and the IROC selection on the example pool."""

import numpy as np
import pytest

from posegen.errors import InfeasibleError
from posegen.select import build_design, d_optimal_weights, detmax_runs, exchange, greedy, iroc, select_k


@pytest.fixture(scope="module")
def design(scene, example_pool):
    built, _ = build_design(scene, example_pool.joints(), [p.chain for p in example_pool.postures])
    return built


@pytest.fixture(scope="module")
def result(design):
    return iroc(design)


def variances(design, weights):
    """d_i = trace(M^-1 I_i), computed plainly."""
    info = sum(w * a.T @ a for w, a in zip(weights, design.regressors, strict=True))
    inverse = np.linalg.inv(info)
    return np.array([np.trace(inverse @ a.T @ a) for a in design.regressors]), info


def test_certificate_holds_at_the_returned_weights(design, result):
    w = result.weights.weights
    assert np.all(w >= 0) and w.sum() == pytest.approx(1.0, abs=1e-12)
    d, _ = variances(design, w)
    gap = d.max() / design.n_params - 1
    assert gap == pytest.approx(result.weights.gap, abs=1e-9)
    assert gap <= 1e-4
    support = w > 1e-6
    assert np.all(d[support] >= design.n_params * (1 - 1e-2))  # support points sit on the bound


def test_no_design_beats_the_certified_weights(design, result):
    """log det M(w') <= log det M(w) + nb log(1 + gap) for every w' (Kiefer-Wolfowitz)."""
    _, info = variances(design, result.weights.weights)
    best = np.linalg.slogdet(info)[1] + design.n_params * np.log1p(result.weights.gap)
    rng = np.random.default_rng(0)
    for w in [np.full(design.size, 1 / design.size), *rng.dirichlet(np.ones(design.size), size=5)]:
        _, other = variances(design, w)
        assert np.linalg.slogdet(other)[1] <= best + 1e-9


def test_weights_do_not_depend_on_the_active_set_heuristic(design, result):
    loose = d_optimal_weights(design, tolerance=1e-2)
    assert loose.gap <= 1e-2 and result.weights.gap <= loose.gap


def test_log_det_never_falls_when_a_posture_is_added(design, result):
    previous = -np.inf
    for k in range(1, 120):
        value = design.log_det(result.ranking[:k])
        score = design.score(result.ranking[:k])
        assert value >= previous - 1e-9
        if np.isfinite(value) and well_identified(design, result.ranking[:k]):
            assert score == pytest.approx(value, abs=1e-4)
        previous = value


def well_identified(design, rows):
    """A set whose information's smallest eigenvalue dwarfs the score's ridge: there log det(I + ridge) is
    log det(I) within nb ridge / lambda_min <= 1e-4 (a weakly identified set scores less, by design)."""
    from posegen.model.design import RIDGE

    smallest = np.linalg.svd(design.stacked(rows), compute_uv=False)[-1] ** 2
    return smallest >= design.n_params * RIDGE / 1e-4


def well_conditioned(design, rows, limit=1e8):
    """A set whose stacked regressor's condition is below ``limit``: there its O1 is accurate to 1e-9
    (just past the rank threshold a set may reach 1e10, where QR's log det moves in the 8th digit)."""
    values = np.linalg.svd(design.stacked(rows), compute_uv=False)
    return values[-1] > 0 and values[0] / values[-1] < limit


def test_o1_curve_and_selection(design, result):
    ks = [k for k, _ in result.curve]
    assert ks[0] == -(-design.n_params // 3) and ks == list(range(ks[0], ks[-1] + 1))
    for k, value in result.curve:
        if well_conditioned(design, result.ranking[:k]):
            assert value == pytest.approx(design.o1(result.ranking[:k]), rel=1e-9, abs=1e-12)
        assert value <= result.o1_star * (1 + 1e-9)  # no k-subset beats the continuous optimum
    k = len(result.selected.rows)
    values = dict(result.curve)
    assert values[k] > 0 and values.get(k + 1, 0) <= values[k]
    assert all(values[j] < values[j + 1] for j in range(ks[0], k) if values[j] > 0)


def test_o1_from_qr_agrees_with_slogdet_on_a_well_conditioned_set(design, result):
    rows = result.ranking[:100]
    stacked = design.stacked(rows)
    sign, value = np.linalg.slogdet(stacked.T @ stacked)
    assert sign > 0
    expected = np.exp((value + design.log_det_pool) / (2 * design.n_params)) / np.sqrt(100)
    assert design.o1(rows) == pytest.approx(expected, rel=1e-8)


def test_greedy_picks_the_best_exact_gain(design):
    first = greedy(design, 60)
    chosen = list(first.rows[:58])  # the set is full rank from here on
    gains = [design.score([*chosen, j]) for j in range(design.size) if j not in chosen]
    assert design.score(list(first.rows[:59])) == pytest.approx(max(gains), abs=1e-6)


def test_k_selection_never_scores_below_the_baselines(design, result):
    for k in (45, 70):
        runs = detmax_runs(design, k, 2, seed=3)
        top = design.score(result.ranking[:k])
        chosen = select_k(design, k, result.ranking, runs)
        assert len(chosen.rows) == k == len(set(chosen.rows))
        assert chosen.score >= top - 1e-9
        assert chosen.score >= max(r.score for r in runs) - 1e-9


def test_exchange_never_lowers_the_score_and_detmax_is_seeded(design):
    start = greedy(design, 70)
    assert exchange(design, start).score >= start.score - 1e-12
    assert detmax_runs(design, 60, 1, seed=5)[0].rows == detmax_runs(design, 60, 1, seed=5)[0].rows


def test_empty_or_rank_deficient_pool(scene, example_pool):
    with pytest.raises(InfeasibleError, match="empty"):
        build_design(scene, np.zeros((0, len(scene.joint_names))), [])
    with pytest.raises(InfeasibleError, match="rank deficient"):
        build_design(scene, example_pool.joints()[:12], [p.chain for p in example_pool.postures[:12]])


def test_k_out_of_range(design):
    """The lower bound is said to be one only: that many postures need not identify every base parameter."""
    with pytest.raises(InfeasibleError, match=rf"choose between {design.fewest()} .*may take more; IROC, k unset"):
        greedy(design, 5)
