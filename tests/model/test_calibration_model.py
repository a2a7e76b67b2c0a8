"""The calibration model: both measurement kinds, compliance and the kind basis."""

import numpy as np
import pytest

from posegen.model import CalibrationModel, Contacts, Kind, Part

COMPLIANCE = {"hip_pitch": ["leg_left_3_joint", "leg_right_3_joint"], "shoulder": ["arm_left_2_joint"]}


@pytest.fixture(scope="module")
def model(scene):
    return CalibrationModel(scene, ["left", "right"], ["a", "b"], COMPLIANCE)


@pytest.fixture(scope="module")
def observations(scene, model):
    rng = np.random.default_rng(4)
    joints = np.tile(scene.reference, (4, 1)) + rng.normal(0.0, 0.1, (4, len(scene.joint_names)))
    return model.observations(Contacts(joints, ("left", "right", "left", "right"), ("a", "a", "b", "b"), tuple("abcd")))


def test_layout_and_basis(model):
    p = model.contact.size
    assert model.size == p + 2 + 3 * 2
    assert np.linalg.matrix_rank(model.basis) == model.size
    kinds = [d.kind for d in model.directions]
    assert kinds.count(Kind.JOINT_OFFSET) == 2 * 15 - 2  # 15 joints per chain, the torso's 2 shared
    assert kinds.count(Kind.AXIS_TILT) == 2 * kinds.count(Kind.JOINT_OFFSET)
    assert kinds.count(Kind.COMPLIANCE) == 2 and kinds.count(Kind.FLOOR) == 6
    parts = {d.owner: d.part for d in model.directions}
    assert parts["torso_1_joint"] == Part.TORSO and parts["leg_left_4_joint"] == Part.LEG
    assert parts["arm_right_3_joint"] == Part.ARM and parts["gripper_left_base_link"] == Part.ARM


def test_jacobian_against_finite_differences(model, observations):
    rng = np.random.default_rng(5)
    x = model.nominal() + model.basis @ rng.normal(0.0, 2e-3, model.size)
    x[model.columns([Kind.COMPLIANCE])] = 2e-4  # rad/N m
    out = model.evaluate(x, observations, jacobian=True)
    h = 1e-7
    for k in range(model.size):
        step = np.zeros(model.size)
        step[k] = h * (1e-2 if model.directions[k].kind == Kind.COMPLIANCE else 1.0)
        plus, minus = model.evaluate(x + step, observations), model.evaluate(x - step, observations)
        fd_contact = (plus.contact - minus.contact) / (2 * step[k])
        fd_floor = (plus.floor - minus.floor) / (2 * step[k])
        assert out.contact_jacobian[:, :, k] == pytest.approx(fd_contact, abs=1e-6, rel=1e-5), k
        assert out.floor_jacobian[:, :, k] == pytest.approx(fd_floor, abs=1e-6, rel=1e-5), k


def test_a_joint_offset_is_a_shift_of_the_joint_angle(scene, model, observations):
    """Along a joint's offset direction the residuals change as if its encoder read more."""
    x = model.nominal()
    base = model.evaluate(x, observations, jacobian=True)
    for name in ("leg_left_2_joint", "torso_1_joint", "arm_right_5_joint"):
        col = next(i for i, d in enumerate(model.directions) if d.owner == name and d.kind == Kind.JOINT_OFFSET)
        along = base.contact_jacobian @ model.basis[:, col]  # (n, 3)
        shifted = observations.contacts.joints.copy()
        shifted[:, scene.joint_index(name)] += 1e-6
        moved = model.evaluate(x, type(observations)(Contacts(shifted, *_meta(observations)), observations.torques))
        assert along == pytest.approx((moved.contact - base.contact) / 1e-6, abs=1e-5)


def test_a_compliance_group_bends_together_under_its_mean_torque(scene, model, observations):
    """Both hip pitch joints give way alike, by the compliance times their mean holding torque, against it."""
    x = model.nominal()
    x[model.columns([Kind.COMPLIANCE])] = (1e-4, 0.0)
    bent = model.deflected(x, observations)
    hips = [scene.joint_index(j) for j in COMPLIANCE["hip_pitch"]]
    load = observations.torques[:, hips].mean(axis=1)
    for hip in hips:
        assert bent[:, hip] - observations.contacts.joints[:, hip] == pytest.approx(-1e-4 * load)
    others = np.setdiff1d(np.arange(len(scene.joint_names)), [scene.joint_index(j) for j in COMPLIANCE["hip_pitch"]])
    assert np.array_equal(bent[:, others], observations.contacts.joints[:, others])


def _meta(observations):
    c = observations.contacts
    return c.chains, c.sessions, c.labels


def test_a_batch_of_parameter_vectors_gives_each_ones_residuals(model, observations):
    """``evaluate_batch`` (the folds' refits) is ``evaluate`` of each vector, the compliant deflection included."""
    rng = np.random.default_rng(6)
    xs = np.array([model.nominal() + model.basis @ rng.normal(0.0, 2e-3, model.size) for _ in range(3)])
    xs[:, model.columns([Kind.COMPLIANCE])] = rng.uniform(0.0, 5e-4, (3, 2))  # each vector its own deflection
    contact, floor = model.evaluate_batch(xs, observations)
    for x, c, f in zip(xs, contact, floor, strict=True):
        one = model.evaluate(x, observations)
        np.testing.assert_allclose(c, one.contact, rtol=0, atol=1e-14)
        np.testing.assert_allclose(f, one.floor, rtol=0, atol=1e-14)
    assert not np.allclose(contact[0], contact[1])  # each vector is judged with its own parameters
