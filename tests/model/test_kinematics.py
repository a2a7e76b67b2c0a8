import numpy as np
import pinocchio as pin
import pytest

from posegen.model import ChainModel, placement_derivatives, placement_matrix, rpy_matrix


def test_rpy_matches_pinocchio():
    phi = np.array([0.3, -0.2, 1.1])
    assert rpy_matrix(phi) == pytest.approx(pin.rpy.rpyToMatrix(*phi))


def test_placement_derivatives_against_finite_differences():
    params = np.array([0.1, -0.2, 0.3, 0.4, -0.5, 0.6])
    analytic = placement_derivatives(params)
    h = 1e-7
    for k in range(6):
        e = np.zeros(6)
        e[k] = h
        fd = (placement_matrix(params + e) - placement_matrix(params - e)) / (2 * h)
        assert analytic[k] == pytest.approx(fd, abs=1e-8)


@pytest.mark.parametrize("chain", ["left", "right"])
def test_chain_matches_pinocchio(scene, chain):
    model = ChainModel(scene, chain)
    assert len(model.joint_indices) == 15  # 6 leg + 2 torso + 7 arm
    assert len(model.elements) == 17
    rng = np.random.default_rng(1)
    joints = rng.uniform(scene.lower, scene.upper, size=(5, len(scene.joint_names)))
    frames = model.sole_to_contact(joints, model.nominal_placements(), np.zeros(3))
    data = scene.model.createData()
    cfg = scene.config.chain(chain)
    for i in range(5):
        pin.framesForwardKinematics(scene.model, data, scene.configuration(joints[i]))
        sole = data.oMf[scene.frame_id(cfg.sole_frame)]
        contact = data.oMf[scene.frame_id(cfg.contact_frame)]
        assert frames[i] == pytest.approx(sole.actInv(contact).homogeneous, abs=1e-12)
