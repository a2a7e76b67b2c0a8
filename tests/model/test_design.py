"""The design's log-det gains agree with the exact QR scores they stand for."""

import numpy as np
import pytest

from posegen.model import build_design


def test_gain_of_each_candidate_is_the_change_of_the_exact_score(scene, example_pool):
    design, _ = build_design(scene, example_pool.joints(), [p.chain for p in example_pool.postures])
    rows = [3, 17, 40, 41, 90]
    gains = design.gains(rows)
    assert np.all(np.isneginf(gains[rows]))
    for j in (0, 5, 99, 150):
        assert gains[j] == pytest.approx(design.score([*rows, j]) - design.score(rows), rel=1e-6, abs=1e-6)
    assert np.all(gains[np.isfinite(gains)] >= 0)  # information never decreases


def test_design_built_in_chunks_is_the_same_design(scene, example_pool, monkeypatch):
    """Large pools build their Jacobians and R factor a chunk at a time: nothing a criterion sees changes."""
    design, _ = build_design(scene, example_pool.joints(), [p.chain for p in example_pool.postures])
    from posegen.model import design as design_module

    monkeypatch.setattr(design_module, "DESIGN_CHUNK", 3 * 7)  # dozens of chunks on the example pool
    chunked, _ = build_design(scene, example_pool.joints(), [p.chain for p in example_pool.postures])
    assert chunked.log_det_pool == pytest.approx(design.log_det_pool, rel=1e-12)
    rows = list(range(0, design.size, 3))
    assert chunked.log_det(rows) == pytest.approx(design.log_det(rows), rel=1e-9)
    # whitening is unique up to the signs of R's rows: the same regressors up to column signs
    assert np.allclose(np.abs(chunked.regressors), np.abs(design.regressors), atol=1e-9)
