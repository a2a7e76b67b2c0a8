"""Collision pairs linearised on a standing robot, and projections that move colliding bodies apart."""

import numpy as np
import pinocchio as pin
import pytest

from posegen.pool.sampler import draw
from posegen.robot import CollisionChecker, Projector, Separation
from posegen.robot.projection import SEPARATION_BUFFER_M


@pytest.fixture(scope="module")
def checker(scene):
    return CollisionChecker(scene, convex=True)


@pytest.fixture(scope="module")
def colliding(scene, checker):
    """The first samples of seed 0 whose projection converges with a pair closer than the margin: (draw, joints)."""
    projector = Projector(scene)
    found = []
    for index in range(80):
        sample = draw(scene, 0, index)
        result = projector.project(sample.joints, sample.chain, scene.spot_world(sample.spot))
        q = scene.configuration(result.joints)
        if result.converged and checker.closest_unless_within(q, sample.chain, scene.margins.collision_m) is None:
            found.append((sample, result.joints))
        if len(found) == 4:
            return found
    raise AssertionError("no colliding projection in 80 samples")


def distances(scene, checker, joints, chain, pairs):
    """Each pair's distance (m) at ``joints``, the base placing the anchor sole (coal, from scratch)."""
    by_pair = {w.pair: w.distance_m for w in checker.witnesses(scene.configuration(joints), chain, np.inf, pairs)}
    return np.array([by_pair[p] for p in pairs])


def test_the_distances_derivative_matches_finite_differences(scene, checker, colliding):
    """A small joint step changes each pair's distance by the gradient's prediction (anchor sole fixed)."""
    separation = Separation(scene, checker)
    rng = np.random.default_rng(3)
    checked = 0
    for sample, joints in colliding:
        rows = separation.rows(joints, sample.chain, 0.03)  # (m,) pairs within 3 cm, one at least penetrating margin
        assert rows.distances_m.min() < scene.margins.collision_m
        step = np.where(scene.locked, 0.0, rng.standard_normal(len(joints)))
        step *= 1e-5 / np.linalg.norm(step)  # rad
        change = (
            distances(scene, checker, joints + step, sample.chain, rows.pairs)
            - distances(scene, checker, joints - step, sample.chain, rows.pairs)
        ) / 2
        predicted = rows.gradient @ step
        np.testing.assert_allclose(predicted, change, rtol=1e-4, atol=1e-12)
        checked += len(rows.pairs)
    assert checked >= 8


def test_half_spaces_keep_the_linearised_distance(scene, checker, colliding):
    sample, joints = colliding[0]
    rows = Separation(scene, checker).rows(joints, sample.chain, 0.02)
    a, b = rows.half_spaces(0.007)
    rng = np.random.default_rng(4)
    for _ in range(20):
        moved = joints + rng.normal(0.0, 0.02, len(joints))
        linear = rows.distances_m + rows.gradient @ (moved - joints)  # (m,) m
        np.testing.assert_array_equal(a @ moved <= b + 1e-12, linear >= 0.007 - 1e-12)
    near = rows.within(0.01)
    assert set(near.pairs) == {p for p, d in zip(rows.pairs, rows.distances_m, strict=True) if d < 0.01}
    assert near.gradient.shape == (len(near.pairs), len(joints))


def test_far_from_everything_no_rows(scene, checker):
    rows = Separation(scene, checker).rows(scene.reference, None, -1.0)
    assert rows.pairs == () and rows.gradient.shape == (0, len(scene.reference))


def test_separate_moves_colliding_bodies_apart_and_keeps_the_contact(scene, checker, colliding):
    """Re-checked independently: every pair (all of coal's) beyond the margin, soles in place, hand flush."""
    projector, separation = Projector(scene), Separation(scene, checker)
    model, data = scene.model, scene.model.createData()
    separated = 0
    for sample, _ in colliding:
        spot = scene.spot_world(sample.spot)
        first = projector.project(sample.joints, sample.chain, spot)
        result = projector.separate(first.joints, sample.chain, spot, separation)
        if not result.converged:
            continue
        separated += 1
        q = scene.configuration(result.joints)
        closest = checker.closest(q, sample.chain)
        assert closest.distance_m >= scene.margins.collision_m + SEPARATION_BUFFER_M / 2 - 1e-9, closest
        pin.framesForwardKinematics(model, data, q)
        for frame, pose in scene.sole_poses.items():
            np.testing.assert_allclose(data.oMf[scene.frame_id(frame)].homogeneous, pose, atol=1e-5)
        chain = scene.chain(sample.chain)
        contact = data.oMf[scene.frame_id(chain.frame(chain.contact_kind))]
        normal = scene.table_pose[:3, 2]
        height = normal @ (contact.translation - scene.table_pose[:3, 3])
        assert height == pytest.approx(chain.contact_kind.lift_m(chain), abs=1e-5)
        assert contact.rotation[:, 2] @ normal == pytest.approx(1.0, abs=1e-8)
        assert np.abs(result.joints - first.joints).max() < 0.5  # a repair, not another posture
    assert separated >= 3
