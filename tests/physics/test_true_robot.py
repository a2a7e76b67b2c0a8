"""The true robot's table: a plane's height, roll and pitch read back from any frame on it."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from posegen.physics.true_robot import plane_offsets
from posegen.robot import offset_matrix


def test_a_plane_s_offsets_are_read_back_from_any_frame_on_it() -> None:
    rng = np.random.default_rng(0)
    for _ in range(20):
        z, roll, pitch = 0.68 + rng.normal(0, 0.05), rng.normal(0, 0.02), rng.normal(0, 0.02)
        frame = offset_matrix(z, roll, pitch)
        assert plane_offsets(frame) == pytest.approx((z, roll, pitch), abs=1e-12)
        moved = np.eye(4)  # along the plane and turned about its normal: the same plane
        moved[:3, :3] = pin.rpy.rpyToMatrix(0.0, 0.0, rng.uniform(-np.pi, np.pi))
        moved[:2, 3] = rng.normal(0, 0.3, 2)
        assert plane_offsets(frame @ moved) == pytest.approx((z, roll, pitch), abs=1e-12)
