"""The order postures are visited in: an open travelling-salesman path (python-tsp).

Distance between two postures: the shortest rest-to-rest time of a straight joint-space
move between them, max_j T(|q_a,j - q_b,j|; v_j, a_j) (s), with T the time of a
trapezoidal (or triangular) velocity profile under the velocity and acceleration limits.
Between contacts the robot starts and ends at rest and most moves never reach the
velocity limit, so this is the robot time a move costs; max_j |dq_j| / v_j, which
ignores accelerations, ranked the moves differently. The path starts at a given posture (half-sitting) and
ends anywhere: the matrix column of the start is zeroed, so returning costs nothing.
Nearest neighbour gives the start order, then 2-opt local search improves it.
"""

from __future__ import annotations

import itertools
import random
from dataclasses import dataclass

import numpy as np
from python_tsp.heuristics import solve_tsp_local_search

from posegen.robot import FloatArray


@dataclass(frozen=True)
class Order:
    """A visiting order."""

    sequence: tuple[int, ...]  # indices of the postures, in visiting order
    length_s: float  # sum of the rest-to-rest times from the start along the sequence
    nearest_neighbour_s: float  # the same for the nearest-neighbour order


def rest_to_rest_time(distance: FloatArray, velocity_limit: FloatArray, acceleration_limit: FloatArray) -> FloatArray:
    """Shortest time of each joint's rest-to-rest move, max over the last axis (joints).

    Args:
        distance: (..., nj) joint distances, rad.
        velocity_limit: (nj,) rad/s.
        acceleration_limit: (nj,) rad/s^2.

    Returns:
        (...) s.

    """
    d, v, a = np.abs(distance), velocity_limit, acceleration_limit
    return np.asarray(np.max(np.where(d <= v**2 / a, 2.0 * np.sqrt(d / a), d / v + v / a), axis=-1))


def transfer_times(points: FloatArray, velocity_limit: FloatArray, acceleration_limit: FloatArray) -> FloatArray:
    """Pairwise rest-to-rest times. points: (n, nj), limits (nj,); returns (n, n) s."""
    return rest_to_rest_time(points[:, None, :] - points[None, :, :], velocity_limit, acceleration_limit)


def _path_length(distances: FloatArray, path: list[int]) -> float:
    return float(sum(distances[a, b] for a, b in itertools.pairwise(path)))


def order_postures(
    start: FloatArray,
    postures: FloatArray,
    velocity_limit: FloatArray,
    acceleration_limit: FloatArray,
    seed: int = 0,
) -> Order:
    """Open-path order of ``postures`` (n, nj) from ``start`` (nj,) under limits (nj,).

    python-tsp's 2-opt visits neighbours in an order drawn from Python's ``random``
    module: it is seeded with ``seed`` for the call, and its state restored after.
    """
    n = len(postures)
    if n == 0:
        return Order((), 0.0, 0.0)
    points = np.vstack([start[None], postures])
    distances = transfer_times(points, velocity_limit, acceleration_limit)
    open_path = distances.copy()
    open_path[:, 0] = 0.0  # coming back to the start is free: an open path
    current, left, greedy = 0, set(range(1, n + 1)), [0]
    while left:
        current = min(left, key=lambda j: (distances[current, j], j))
        greedy.append(current)
        left.remove(current)
    if n >= 3:
        state = random.getstate()
        try:
            random.seed(seed)
            permutation, _ = solve_tsp_local_search(open_path, x0=greedy, perturbation_scheme="two_opt")
        finally:
            random.setstate(state)
        path = [int(p) for p in permutation]
    else:
        path = greedy
    if _path_length(distances, path) > _path_length(distances, greedy):
        path = greedy  # local search keeps the best it saw; this only guards the contract
    return Order(
        sequence=tuple(p - 1 for p in path[1:]),
        length_s=_path_length(distances, path),
        nearest_neighbour_s=_path_length(distances, greedy),
    )
