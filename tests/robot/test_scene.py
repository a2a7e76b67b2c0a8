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


@pytest.fixture(scope="module")
def waist_scene(tmp_path_factory):
    """The draft of the synthetic humanoid rooted at its torso, two waist joints down to the pelvis, as a scene."""
    from posegen.draft import write_draft
    from posegen.robot import Scene, load_config
    from tests.draft.humanoid_urdf import humanoid_urdf

    folder = tmp_path_factory.mktemp("waist")
    config = folder / "config.yaml"
    write_draft(str(humanoid_urdf(folder / "description", "z", waist=2)), str(config), samples=20)
    return Scene(load_config(config))


def test_legs_below_a_waist_stop_at_the_pelvis(waist_scene):
    scene = waist_scene
    hip_to_ankle = ["hip_yaw", "hip_roll", "hip_pitch", "knee", "ankle_pitch", "ankle_roll"]
    for sole, side in zip(scene.stance.sole_frames, "lr", strict=True):
        assert [scene.joint_names[i] for i in scene.leg_joints(sole)] == [f"{side}_{j}" for j in hip_to_ankle[::-1]]
    waist = [scene.joint_index(name) for name in ("waist", "waist_pitch")]
    assert not set(waist) & set(scene.stance_leg_joints()) and not scene.locked[waist].any()
    assert len(scene.stance_leg_joints()) == 12


def test_close_stance_below_a_waist_moves_the_second_leg_alone(waist_scene):
    """From perturbed states (waist, both legs, arms), both soles close exactly; waist and anchor leg stay put."""
    scene = waist_scene
    closing = set(scene.leg_joints(scene.second_sole))
    free = np.flatnonzero(~scene.locked)
    data = scene.model.createData()
    rng = np.random.default_rng(4)
    for _ in range(5):
        joints = scene.reference.copy()
        joints[free] += rng.uniform(-0.05, 0.05, len(free))
        closed = scene.close_stance(joints)
        assert closed is not None
        assert set(np.flatnonzero(closed != joints)) <= closing  # waist, anchor leg, arms untouched
        pin.framesForwardKinematics(scene.model, data, scene.configuration(closed))
        for sole in scene.stance.sole_frames:
            pose = pin.SE3(scene.sole_poses[sole])
            assert np.linalg.norm(pin.log6(data.oMf[scene.frame_id(sole)].actInv(pose)).vector) < 1e-10


def test_idle_joints_move_neither_the_contact_nor_a_sole_and_every_other_free_joint_does(scene, config):
    data = scene.model.createData()
    joints = scene.reference.copy()

    def frames_at(angles, chain):
        pin.framesForwardKinematics(scene.model, data, scene.configuration(angles))
        names = [chain.contact_frame, *scene.sole_poses]
        return np.array([data.oMf[scene.frame_id(n)].homogeneous for n in names])

    for chain in config.chains:
        idle = scene.idle_joints(chain.name)
        at_rest = frames_at(joints, chain)
        for j in np.flatnonzero(~scene.locked):
            moved = joints.copy()
            moved[j] += 0.1
            still = np.allclose(frames_at(moved, chain), at_rest, atol=1e-12)
            assert still == (j in idle), (chain.name, scene.joint_names[j])
        idle.clear()  # the caller's copy: the scene's answer stays
        assert scene.idle_joints(chain.name)
