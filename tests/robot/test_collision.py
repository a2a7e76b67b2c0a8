import numpy as np
import pinocchio as pin
import pytest

from posegen.robot import TABLE, CollisionChecker


@pytest.fixture(scope="module")
def checkers(scene):
    return CollisionChecker(scene, convex=True), CollisionChecker(scene, convex=False)


def pair_distances(checker, scene, q):
    data = pin.GeometryData(checker.geom)
    pin.computeDistances(scene.model, scene.model.createData(), checker.geom, data, q)
    return np.array([r.min_distance for r in data.distanceResults])


def test_hulls_never_report_more_than_meshes(scene, checkers):
    """The sampler's hull check is conservative: hull distance <= mesh distance, pair by pair."""
    hulls, meshes = checkers
    rng = np.random.default_rng(3)
    for _ in range(3):
        q = scene.configuration(rng.uniform(scene.lower, scene.upper))
        hull_d = pair_distances(hulls, scene, q)
        mesh_d = pair_distances(meshes, scene, q)
        near = mesh_d < 0.05  # the pairs that matter for a margin
        assert np.all(hull_d[near] <= mesh_d[near] + 1e-6)


def test_reference_posture_is_collision_free(scene, checkers):
    hulls, meshes = checkers
    q = scene.configuration(scene.reference)
    assert hulls.closest(q, None).distance_m > 0
    assert meshes.colliding_pairs(q, None, 0.0) == []


def test_table_and_floor_are_obstacles(scene, checkers):
    hulls, _ = checkers
    q = scene.configuration(scene.reference)
    q[2] -= 0.2  # sink the robot into the floor: the ankles (not the soles' links) hit it
    closest = hulls.closest(q, None)
    assert closest.distance_m < 0 and "floor" in closest.pair
    q = scene.configuration(scene.reference)
    q[0] += 0.5  # walk into the table
    assert TABLE in hulls.closest(q, None).pair


def test_fingertips_may_touch_the_table_only_in_contact(scene, checkers, small_pool):
    hulls, _ = checkers
    posture = small_pool.postures[0]
    q = scene.configuration(np.array(posture.joints))
    assert hulls.closest(q, posture.chain).distance_m >= scene.config.margins.collision_m
    closest = hulls.closest(q, None)  # same posture, but the contact is not exempted
    assert closest.distance_m < 1e-3 and TABLE in closest.pair


def test_a_table_margin_widens_the_table_pairs_only(scene, checkers):
    """Free motions keep the robot further from the table than from itself: the table's pairs get their own margin."""
    hulls, _ = checkers
    q = scene.configuration(scene.reference)
    q[0] += 0.13  # toward the table: its nearest body about 3 cm away
    distances = pair_distances(hulls, scene, q)
    table = np.array([TABLE in hulls._pair_names(k) for k in range(hulls.n_pairs)])
    near = float(distances[table].min())
    assert 0.0 < near < 0.1 and distances[~table].min() > 0.0
    margins = hulls.pair_margins(0.0, near + 0.002)
    assert np.all(margins[table] == near + 0.002) and np.all(margins[~table] == 0.0)
    assert np.array_equal(hulls.pair_margins(0.01, None), np.full(hulls.n_pairs, 0.01))
    assert np.all(hulls.pair_margins(0.01, 0.002) == 0.01)  # never below the collision margin
    assert not hulls.collides(q, None, 0.0)
    assert not hulls.collides(q, None, 0.0, near - 0.002)
    assert hulls.collides(q, None, 0.0, near + 0.002)
    hits = hulls.colliding_pairs(q, None, 0.0, near + 0.002)
    assert hits and all(TABLE in hit.pair for hit in hits) and hits[0].distance_m == pytest.approx(near, abs=1e-6)
    assert all(hit.margin_m == near + 0.002 and hit.excess_m == near + 0.002 - hit.distance_m for hit in hits)
    assert not hulls.collides(q, None, 0.0)  # the margins set back for the next query
