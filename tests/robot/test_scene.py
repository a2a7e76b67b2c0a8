import numpy as np
import pinocchio as pin
import pytest


def test_actuated_joints_and_limits(scene):
    assert len(scene.joint_names) == 32
    assert np.all(scene.lower < scene.upper)
    assert np.all(scene.velocity_limit > 0)


def test_soles_are_flat_on_the_floor_at_the_reference_posture(scene):
    for pose in scene.sole_poses.values():
        assert pose[2, 3] == 0.0
        assert pose[:3, 2] == pytest.approx([0, 0, 1])
    q = scene.configuration(scene.reference)
    data = scene.model.createData()
    pin.framesForwardKinematics(scene.model, data, q)
    for frame, pose in scene.sole_poses.items():
        actual = data.oMf[scene.frame_id(frame)].homogeneous
        assert actual[:2, 3] == pytest.approx(pose[:2, 3], abs=1e-3)


def test_contact_frame_is_centroid_of_fingertip_ends(scene, config):
    data = scene.model.createData()
    q = scene.configuration(scene.reference)
    pin.framesForwardKinematics(scene.model, data, q)
    for chain in config.chains:
        contact = data.oMf[scene.frame_id(chain.contact_frame)]
        grip = data.oMf[scene.frame_id(chain.gripper_frame)]
        ends = [
            data.oMf[scene.frame_id(f)].translation - chain.fingertip_length_m * grip.rotation[:, 2]
            for f in chain.fingertip_frames
        ]
        assert contact.translation == pytest.approx(np.mean(ends, axis=0), abs=1e-9)
        # z along the gripper normal, pointing back towards the gripper
        assert contact.rotation[:, 2] == pytest.approx(grip.rotation[:, 2], abs=1e-9)
        for end in ends:  # all ends lie in the contact plane
            assert abs((end - contact.translation) @ contact.rotation[:, 2]) < 1e-9


def test_configuration_places_the_anchor_sole(scene):
    rng = np.random.default_rng(0)
    joints = rng.uniform(scene.lower, scene.upper)
    q = scene.configuration(joints)
    data = scene.model.createData()
    pin.framesForwardKinematics(scene.model, data, q)
    anchor = data.oMf[scene.frame_id(scene.anchor_sole)].homogeneous
    assert anchor == pytest.approx(scene.sole_poses[scene.anchor_sole], abs=1e-12)
    assert scene.joints_of(q) == pytest.approx(joints)


def test_support_polygon_contains_both_feet(scene):
    from posegen.robot import polygon_margin

    for pose in scene.sole_poses.values():
        assert polygon_margin(scene.support_polygon, pose[:2, 3]) > 0.05
