"""The hot path's solves: the same numbers as numpy's, to the last bit, and its errors."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from posegen.physics.lapack import Factored, solve


@pytest.mark.parametrize("rows,columns", [(2, 2), (6, 7), (7, 6), (12, 17)])
def test_solve_gives_numpy_s_numbers(rows: int, columns: int) -> None:
    rng = np.random.default_rng(rows * columns)
    for _ in range(200):
        jacobian = rng.normal(size=(rows, columns))
        gram = jacobian @ jacobian.T + 1e-4 * np.eye(rows)  # the damped solves of the joint offsets
        vector = rng.normal(size=rows)
        assert np.array_equal(solve(gram, vector), np.linalg.solve(gram, vector))


def test_a_factored_pose_gives_numpy_s_numbers() -> None:
    rng = np.random.default_rng(1)
    pin.seed(1)
    for _ in range(200):
        pose = pin.SE3.Random().homogeneous
        given = pose.copy()
        factored = Factored(pose)
        pose[0, 0] += 1.0  # the factors are the matrix's when it was given
        for _ in range(3):
            point = np.array([*rng.normal(size=2), 0.0, 1.0])
            assert np.array_equal(factored.solve(point), np.linalg.solve(given, point))


def test_inputs_are_left_alone_and_singular_matrices_are_refused() -> None:
    matrix, vector = np.array([[2.0, 1.0], [1.0, 3.0]]), np.array([1.0, 2.0])
    kept = matrix.copy(), vector.copy()
    solve(matrix, vector)
    Factored(matrix).solve(vector)
    assert np.array_equal(matrix, kept[0]) and np.array_equal(vector, kept[1])
    with pytest.raises(np.linalg.LinAlgError):
        solve(np.ones((2, 2)), vector)
    with pytest.raises(np.linalg.LinAlgError):
        Factored(np.ones((2, 2)))
