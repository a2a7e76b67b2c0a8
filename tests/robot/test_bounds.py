"""Bounding spheres: never above a pair's true distance; the screened check equals the full one."""

import numpy as np
import pinocchio as pin
import pytest

from posegen.robot import CollisionChecker
from posegen.robot.bounds import BoundingSpheres


@pytest.fixture(scope="module")
def hulls(scene):
    return CollisionChecker(scene, convex=True)


def configurations(scene, small_pool, count=12):
    """Accepted contact postures (clear of collisions) and uniform samples (most collide)."""
    rng = np.random.default_rng(11)
    feasible = [(scene.configuration(np.array(p.joints)), p.chain) for p in small_pool.postures[:count]]
    uniform = [(scene.configuration(rng.uniform(scene.lower, scene.upper)), None) for _ in range(count)]
    return feasible + uniform


def test_bounds_never_exceed_exact_distances(scene, hulls, small_pool):
    spheres = BoundingSpheres(hulls.geom)
    for q, _ in configurations(scene, small_pool):
        data = pin.GeometryData(hulls.geom)
        pin.computeDistances(scene.model, scene.model.createData(), hulls.geom, data, q)
        exact = np.array([r.min_distance for r in data.distanceResults])
        bounds = spheres.lower_bounds(data)
        assert np.all(bounds <= exact + 1e-12), float((exact - bounds).min())
        assert np.mean(bounds > 0.05) > 0.5  # and they are informative: most pairs are screened out


def test_screened_check_is_the_full_check(scene, hulls, small_pool):
    margin = scene.margins.collision_m
    seen_collision = seen_clear = False
    for q, chain in configurations(scene, small_pool):
        full = hulls.closest(q, chain)
        screened = hulls.closest_unless_within(q, chain, margin)
        if full.distance_m < margin:
            assert screened is None
            seen_collision = True
        else:
            assert screened == full  # same pair, same distance, bit for bit
            seen_clear = True
    assert seen_collision and seen_clear


def test_screened_check_does_not_depend_on_history(scene, small_pool):
    cases = configurations(scene, small_pool)
    forward = CollisionChecker(scene, convex=True)
    backward = CollisionChecker(scene, convex=True)
    margin = scene.margins.collision_m
    first = [forward.closest_unless_within(q, chain, margin) for q, chain in cases]
    second = [backward.closest_unless_within(q, chain, margin) for q, chain in reversed(cases)][::-1]
    assert first == second


def test_collides_asks_coal_only_about_pairs_that_could_be_within_the_margin(scene, hulls, small_pool):
    """The screened yes/no equals checking every pair, at the planner's margin and a larger one."""
    verdicts = []
    for q, chain in configurations(scene, small_pool):
        for margin in (0.005, 0.05):
            data = hulls._fresh_data(chain)
            for request in data.collisionRequests:
                request.security_margin = margin
            full = bool(pin.computeCollisions(scene.model, hulls._model_data, hulls.geom, data, q, True))
            assert hulls.collides(q, chain, margin) == full
            verdicts.append(full)
    assert 0 < sum(verdicts) < len(verdicts)  # both answers were exercised


def test_pairs_are_visited_in_the_order_of_a_stable_sort_of_their_bounds():
    """Sorting the near pairs first, the rest when reached, is one stable argsort (ties, inactive and nan included)."""
    from posegen.robot.collision import _by_bound

    rng = np.random.default_rng(0)
    for _ in range(500):
        n = int(rng.integers(1, 60))
        bounds = np.round(rng.normal(0.02, 0.03, n), 3)  # rounded: ties
        bounds[rng.random(n) < 0.2] = np.inf
        bounds[rng.random(n) < 0.05] = np.nan
        split = float(rng.normal(0.02, 0.03))
        assert list(_by_bound(bounds, split)) == np.argsort(bounds, kind="stable").tolist()
