"""The floor closure: second sole in the first sole's frame."""

import numpy as np
import pytest

from posegen.errors import InfeasibleError
from posegen.model import ContactModel
from posegen.model.floor_model import FloorModel


@pytest.fixture(scope="module")
def floor(scene):
    return FloorModel(ContactModel(scene, ["left", "right"], ["a"]))


def test_closed_stance_is_flat_and_where_the_reference_puts_it(scene, floor):
    """Postures whose second leg was closed onto its sole: height, roll, pitch zero; x, y, yaw the reference's."""
    rng = np.random.default_rng(2)
    legs = scene.stance_leg_joints()
    closed = []
    while len(closed) < 4:
        sample = scene.reference.copy()
        sample[legs] += rng.uniform(-0.15, 0.15, len(legs))
        out = scene.close_stance(sample)
        if out is not None:
            closed.append(out)
    meas = floor.measure(floor.contacts.nominal(), np.array(closed))
    relative = np.linalg.inv(scene.sole_poses[scene.anchor_sole]) @ scene.sole_poses[scene.second_sole]
    assert meas[:, 2:5] == pytest.approx(0.0, abs=1e-9)
    assert meas[:, 0] == pytest.approx(relative[0, 3], abs=1e-9)
    assert meas[:, 1] == pytest.approx(relative[1, 3], abs=1e-9)
    frames = floor.second_sole_frames(floor.contacts.nominal()[None], np.array(closed))  # (1, 4, 4, 4)
    assert frames.shape == (1, 4, 4, 4) and np.allclose(frames[0], relative, atol=1e-9)  # the whole pose


def test_derivatives_against_finite_differences(scene, floor):
    rng = np.random.default_rng(0)
    joints = rng.uniform(scene.lower, scene.upper, size=(3, len(scene.joint_names)))
    model = floor.contacts
    theta = model.nominal() + rng.normal(0.0, 0.01, model.size)
    _, d_theta, d_joints = floor.derivatives(theta, joints)
    h = 1e-6
    names = [e.name for leg in floor.legs for e in leg.elements if e.reverse]
    legs = [c for name in names for c in model.placement_columns(name)]
    for k in legs:
        step = np.zeros(model.size)
        step[k] = h
        fd = (floor.measure(theta + step, joints) - floor.measure(theta - step, joints)) / (2 * h)
        assert d_theta[:, :, k] == pytest.approx(fd, abs=1e-7), model.parameters[k].name
    others = np.setdiff1d(np.arange(model.size), legs)
    assert np.all(d_theta[:, :, others] == 0.0)  # arms, torso, contacts and planes do not move the feet
    for j in range(len(scene.joint_names)):
        step = np.zeros_like(joints)
        step[:, j] = h
        fd = (floor.measure(theta, joints + step) - floor.measure(theta, joints - step)) / (2 * h)
        assert d_joints[:, :, j] == pytest.approx(fd, abs=1e-7), scene.joint_names[j]


def test_one_chain_has_no_floor_equations(scene):
    with pytest.raises(InfeasibleError, match="no chain starts at"):
        FloorModel(ContactModel(scene, ["left"], ["a"]))
