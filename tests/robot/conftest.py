"""A moving robot shared by the tests of the floor's wrench and of the torques at speed."""

import numpy as np
import pinocchio as pin
import pytest


@pytest.fixture(scope="module")
def motion(scene):
    """A smooth joint motion q(t) = q0 + v0 t + a0 t^2 / 2 from a perturbed reference posture: (nj,) each."""
    rng = np.random.default_rng(11)
    free = ~scene.locked
    q0 = scene.reference + np.where(free, rng.normal(0.0, 0.05, len(free)), 0.0)
    v0 = np.where(free, rng.normal(0.0, 0.4, len(free)), 0.0)
    a0 = np.where(free, rng.normal(0.0, 1.0, len(free)), 0.0)
    return q0, v0, a0


def full_state(scene, joints, velocity, acceleration):
    """Configuration, velocity and acceleration (nq,), (nv,), (nv,), the base moving so the anchor sole stays still."""
    model, data = scene.model, scene.model.createData()
    q = scene.configuration(joints)
    v, a = np.zeros(model.nv), np.zeros(model.nv)
    v[scene.velocity_indices()], a[scene.velocity_indices()] = velocity, acceleration
    anchor_id = scene.frame_id(scene.anchor_sole)
    pin.computeJointJacobians(model, data, q)
    anchor = pin.getFrameJacobian(model, data, anchor_id, pin.LOCAL)
    v[:6] = -np.linalg.solve(anchor[:, :6], anchor[:, 6:] @ v[6:])
    pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
    drift = pin.getFrameAcceleration(model, data, anchor_id, pin.LOCAL).vector
    a[:6] = -np.linalg.solve(anchor[:, :6], anchor[:, 6:] @ a[6:] + drift)
    return q, v, a
