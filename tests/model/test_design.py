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
