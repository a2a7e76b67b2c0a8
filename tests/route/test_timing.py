import itertools

import numpy as np
import pytest

from posegen.route import SAFETY, hold, parameterize

V = np.array([1.0, 2.0, 0.5])
A = np.array([1.5, 1.5, 1.5])


def stop_and_go(points):
    """Time of rest-to-rest bang-bang moves between every pair of waypoints: an upper bound."""
    total = 0.0
    for a, b in itertools.pairwise(points):
        d = np.abs(b - a)
        v, acc = SAFETY * V, SAFETY * A
        total += float(np.max(np.where(d <= v**2 / acc, 2 * np.sqrt(d / acc), d / v + v / acc)))
    return total


def sharp_turn_path():
    line = np.linspace([0.0, 0.0, 0.0], [0.08, 0.02, 0.0], 8)
    return np.vstack([line, line[-1] + [0.0, 0.0, 0.012]])  # a last step at right angles


@pytest.mark.parametrize("points", [sharp_turn_path(), np.cumsum(np.random.default_rng(0).normal(0, 0.02, (40, 3)), 0)])
def test_limits_rest_to_rest_and_never_slower_than_stop_and_go(points):
    timed = parameterize(points, V, A)
    assert np.all(np.diff(timed.times) > 0)
    assert np.all(np.abs(timed.velocities) <= V * (1 + 1e-9))
    assert np.all(np.abs(timed.accelerations) <= A * (1 + 1e-9))
    assert np.all(timed.velocities[0] == 0) and np.all(timed.velocities[-1] == 0)
    assert timed.positions == pytest.approx(points)
    assert timed.times[-1] <= stop_and_go(points) * (1 + 1e-9)  # a near-zero path speed would break this


def test_two_points_and_duplicates():
    timed = parameterize(np.array([[0.0, 0, 0], [0.0, 0, 0], [0.3, 0, 0]]), V, A)
    assert len(timed.times) == 2 and timed.times[-1] == pytest.approx(stop_and_go(timed.positions))
    still = parameterize(np.zeros((3, 3)), V, A)
    assert len(still.times) == 1


def test_hold():
    timed = hold(np.array([0.1, 0.2, 0.3]), 2.0)
    assert list(timed.times) == [0.0, 2.0] and np.all(timed.velocities == 0)


def test_per_waypoint_limits_hold_at_every_point_and_positions_agree_with_velocities():
    """Slow at both ends, fast in the middle: one timing, each point within its own limit."""
    from posegen.route.timing import consistency_ratio

    points = np.cumsum(np.random.default_rng(1).normal(0, 0.02, (60, 3)), 0)
    limits = np.tile(V, (60, 1))
    limits[:15] *= 0.1
    limits[-15:] *= 0.1
    timed = parameterize(points, limits, A)
    assert np.all(np.abs(timed.velocities) <= limits * (1 + 1e-9))
    assert np.all(np.abs(timed.accelerations) <= A * (1 + 1e-9))
    assert consistency_ratio(timed, A) <= 1 + 1e-9
    assert timed.times[-1] > parameterize(points, V, A).times[-1]  # the slow ends cost time
