"""Joint torques that hold a standing posture against gravity.

With both soles on the floor the robot is a closed chain: the floor's wrenches on the
two soles balance the weight (six equations) and the split between the feet is not
determined by statics alone. posegen takes the split of least size (forces in N and
moments in N m over a ``MOMENT_ARM_M`` lever weighed alike), the usual choice when
nothing is known about the feet. The arm in contact is taken as unloaded: the
force-controlled contact presses with a small force that is not recorded.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from posegen.robot.geometry import FloatArray
from posegen.robot.scene import Scene

MOMENT_ARM_M = 0.1  # a moment of 1 N m weighs like a force of 10 N in the wrench split


def gravity_torques(scene: Scene, joints: FloatArray) -> FloatArray:
    """Joint torques (N m) that hold each posture still, both soles loaded.

    Args:
        scene: Scene (its model has the URDF's masses and inertias).
        joints: (n, nj) joint angles, rad.

    Returns:
        (n, nj) torques in the scene's joint order, N m (positive about each joint's axis).

    """
    model = scene.model
    data = model.createData()
    soles = [scene.frame_id(frame) for frame in scene.stance.sole_frames]
    velocity = scene.velocity_indices()
    weight = np.tile([1.0, 1.0, 1.0, MOMENT_ARM_M, MOMENT_ARM_M, MOMENT_ARM_M], len(soles))  # wrench = weight * scaled
    joints = np.atleast_2d(joints)
    out = np.zeros((joints.shape[0], len(scene.joint_names)))
    for i, posture in enumerate(joints):
        q = scene.configuration(posture)
        gravity = pin.computeGeneralizedGravity(model, data, q)  # (nv,)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        contact = np.vstack([pin.getFrameJacobian(model, data, f, pin.LOCAL) for f in soles])  # (6 k, nv)
        base = contact[:, :6].T * weight[None, :]  # free-flyer rows, acting on the scaled wrenches
        scaled = np.linalg.lstsq(base, gravity[:6], rcond=None)[0]  # least-size wrenches balancing the weight
        torque = gravity - contact.T @ (scaled * weight)
        out[i] = torque[velocity]
    return out
