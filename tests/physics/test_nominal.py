"""The controllers' nominal robot: its base as the IMU tilts it, its Jacobians against finite differences."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from posegen.physics.nominal import NominalRobot
from posegen.physics.tool import Tool
from posegen.robot import Scene


def _posture(scene: Scene) -> np.ndarray:
    rng = np.random.default_rng(5)
    joints = scene.reference + rng.uniform(-0.1, 0.1, len(scene.reference))
    return np.where(scene.locked, scene.reference, np.clip(joints, scene.lower, scene.upper))


def test_the_imu_turns_the_base_about_the_anchor_sole(scene: Scene, tools: dict[str, Tool]) -> None:
    """The anchor sole's origin stays at its place; the base's roll and pitch are the IMU's, its yaw the kinematics'."""
    robot = NominalRobot(scene, tools)
    joints = _posture(scene)
    robot.update(joints)
    flat_base = pin.XYZQUATToSE3(robot.q[:7]).rotation
    imu = pin.rpy.rpyToMatrix(0.03, -0.02, 0.4)  # a yaw the kinematics do not have
    robot.update(joints, imu)
    anchor = robot.sole_poses[0]
    place = scene.sole_poses[scene.anchor_sole]
    assert np.allclose(anchor[:3, 3], place[:3, 3], rtol=0.0, atol=1e-12)
    base = pin.XYZQUATToSE3(robot.q[:7]).rotation
    assert np.allclose(pin.rpy.matrixToRpy(base)[:2], [0.03, -0.02], rtol=0.0, atol=1e-12)
    yaw = np.arctan2(base[1, 0], base[0, 0])
    assert np.isclose(yaw, np.arctan2(flat_base[1, 0], flat_base[0, 0]), rtol=0.0, atol=1e-12)


def test_joint_jacobian_is_the_frames_motion_on_the_base(scene: Scene, tools: dict[str, Tool]) -> None:
    """Each column: the frame's twist (world axes at the frame) as one joint moves, the base still (differences)."""
    robot = NominalRobot(scene, tools)
    joints = _posture(scene)
    robot.update(joints)
    frame = robot.contact_frames["left"]
    chosen = [scene.joint_index(n) for n in ("torso_1_joint", "arm_left_2_joint", "arm_left_5_joint")]
    jacobian = robot.joint_jacobian(frame, chosen)  # (6, 3)
    assert np.array_equal(jacobian, robot.frame_jacobian(frame)[:, 6 + np.array(chosen)])
    model, data = scene.model, scene.model.createData()
    step = 1e-6
    for column, j in enumerate(chosen):
        poses = []
        for sign in (-1.0, 1.0):
            q = robot.q.copy()  # the base where the robot believes it is
            q[scene.velocity_indices()[j] + 1] += sign * step
            pin.framesForwardKinematics(model, data, q)
            poses.append(data.oMf[frame].copy())
        linear = (poses[1].translation - poses[0].translation) / (2 * step)
        angular = pin.log3(poses[1].rotation @ poses[0].rotation.T) / (2 * step)
        assert np.allclose(jacobian[:, column], np.concatenate([linear, angular]), rtol=0.0, atol=1e-6)


def test_com_is_a_new_array_renewed_by_each_update(scene: Scene, tools: dict[str, Tool]) -> None:
    robot = NominalRobot(scene, tools)
    robot.update(scene.reference)
    first = robot.com()
    first[:] = 0.0  # a caller's change stays the caller's
    assert np.array_equal(robot.com(), pin.centerOfMass(scene.model, scene.model.createData(), robot.q))
    robot.update(_posture(scene))
    assert np.array_equal(robot.com(), pin.centerOfMass(scene.model, scene.model.createData(), robot.q))
