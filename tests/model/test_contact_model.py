import numpy as np
import pytest

from posegen.model import ContactModel, Contacts, Group


@pytest.fixture(scope="module")
def model(scene):
    return ContactModel(scene, ["left", "right"], ["a", "b"])


def test_parameter_layout(model):
    # 17 placements x 6 per chain, the torso's 2 placements shared, 3 contact offsets per chain, 3 per plane
    assert model.size == 2 * 17 * 6 - 2 * 6 + 2 * 3 + 2 * 3
    assert len(model.columns(Group.PLANE)) == 6 and len(model.columns(Group.CONTACT)) == 6
    assert "torso_1_joint.px" in model.index and "plane@b.pitch" in model.index


def test_jacobian_against_finite_differences(scene, model):
    rng = np.random.default_rng(0)
    joints = rng.uniform(scene.lower, scene.upper, size=(6, len(scene.joint_names)))
    contacts = Contacts(joints, ("left", "right") * 3, ("a", "a", "b", "b", "a", "b"), tuple("abcdef"))
    theta = model.nominal() + rng.normal(0.0, 0.01, model.size)
    _, jac = model.jacobian(theta, contacts)
    h = 1e-6
    for k in range(model.size):
        step = np.zeros(model.size)
        step[k] = h
        fd = (model.residuals(theta + step, contacts) - model.residuals(theta - step, contacts)) / (2 * h)
        assert jac[:, :, k] == pytest.approx(fd, abs=1e-7), model.parameters[k].name


def test_plane_offsets_shift_the_measurement(scene, model):
    joints = np.tile(scene.reference, (1, 1))
    contacts = Contacts(joints, ("left",), ("a",), ("x",))
    theta = model.nominal()
    before = model.residuals(theta, contacts)
    theta[model.index["plane@a.z"]] += 0.01
    after = model.residuals(theta, contacts)
    assert after[0, 0] == pytest.approx(before[0, 0] - 0.01)


def test_joint_derivatives_against_finite_differences(scene, model):
    rng = np.random.default_rng(1)
    joints = rng.uniform(scene.lower, scene.upper, size=(4, len(scene.joint_names)))
    contacts = Contacts(joints, ("left", "right", "left", "right"), ("a", "a", "b", "b"), tuple("abcd"))
    theta = model.nominal() + rng.normal(0.0, 0.01, model.size)
    res, jac, d_joints = model.derivatives(theta, contacts)
    assert res == pytest.approx(model.residuals(theta, contacts))
    assert jac == pytest.approx(model.jacobian(theta, contacts)[1])
    h = 1e-6
    for j in range(len(scene.joint_names)):
        step = np.zeros_like(joints)
        step[:, j] = h
        plus = Contacts(joints + step, contacts.chains, contacts.sessions, contacts.labels)
        minus = Contacts(joints - step, contacts.chains, contacts.sessions, contacts.labels)
        fd = (model.residuals(theta, plus) - model.residuals(theta, minus)) / (2 * h)
        assert d_joints[:, :, j] == pytest.approx(fd, abs=1e-7), scene.joint_names[j]
