"""The steps a Scene is built in, each alone: what it makes, checked against pinocchio or the config."""

import dataclasses

import numpy as np
import pinocchio as pin
import pytest

from posegen.errors import ConfigError
from posegen.robot import Scene, parse_config, polygon_margin
from posegen.robot.scene_parts import (
    actuated_joints,
    apply_additions,
    check_names,
    contact_placements,
    limit_margins,
    load_description,
    read_srdf_states,
    reference_configuration,
    stand,
    table_pose,
    table_spots,
    velocity_limits,
)
from tests.conftest import point_config_data


@pytest.fixture(scope="module")
def point_config():
    return parse_config(point_config_data())


@pytest.fixture(scope="module")
def declared(point_config):
    return load_description(point_config)


def test_load_description_declares_the_configs_frames_where_it_says(declared, point_config, point_scene):
    data = declared.model.createData()
    pin.framesForwardKinematics(declared.model, data, pin.neutral(declared.model))
    for frame in point_config.frames:
        assert declared.model.existFrame(frame.name)
        parent = data.oMf[declared.model.getFrameId(frame.parent)]
        here = parent.actInv(data.oMf[declared.model.getFrameId(frame.name)])
        assert here.translation == pytest.approx(frame.xyz_m, abs=1e-12)
    assert not any(declared.model.existFrame(c.contact_frame) for c in point_config.chains)  # not added yet
    assert declared.files.urdf.is_file() and declared.files.sha256() == point_scene.files.sha256()


def test_check_names_names_the_field_of_a_missing_frame(declared, point_config):
    check_names(declared.model, point_config)  # every name exists
    soles = dataclasses.replace(point_config.stance, sole_frames=("left_sole_lnk", "right_sole_link"))
    with pytest.raises(ConfigError, match=r"'left_sole_lnk'.*did you mean left_sole_link.*\(stance\.sole_frames\)$"):
        check_names(declared.model, dataclasses.replace(point_config, stance=soles))
    chains = tuple(dataclasses.replace(c, point_frame=f"{c.name}_top") for c in point_config.chains)
    with pytest.raises(ConfigError, match=rf"'{chains[0].name}_top'.*\(chains\.{chains[0].name}\.point_frame\)$"):
        check_names(declared.model, dataclasses.replace(point_config, chains=chains))


def test_apply_additions_adds_the_contact_frames_and_nothing_else(declared, point_config):
    urdf_xml, model = apply_additions(declared, point_config)
    links = [{f.name for f in m.frames if f.type == pin.FrameType.BODY} for m in (model, declared.model)]
    added = links[0] - links[1]
    assert added == {c.contact_frame for c in point_config.chains if c.fingertip_frames} != set()
    assert (model.nq, model.nv, list(model.names)) == (declared.model.nq, declared.model.nv, list(declared.model.names))
    assert pin.buildModelFromXML(urdf_xml, pin.JointModelFreeFlyer()).nframes == model.nframes


def test_contact_placements_are_the_frames_in_their_grippers_at_the_held_posture(scene, point_scene):
    held = scene.model_configuration(scene.locked_values)
    data = scene.model.createData()
    pin.framesForwardKinematics(scene.model, data, held)
    flush, point = contact_placements(scene.model, scene.chains, held)
    assert set(flush) == {c.name for c in scene.chains} and not point  # the default chains are flush
    for chain in scene.chains:
        grip, contact = (data.oMf[scene.frame_id(f)] for f in (chain.gripper_frame, chain.contact_frame))
        assert flush[chain.name].homogeneous == pytest.approx(grip.actInv(contact).homogeneous, abs=1e-12)
    held = point_scene.model_configuration(point_scene.locked_values)
    data = point_scene.model.createData()
    pin.framesForwardKinematics(point_scene.model, data, held)
    _, point = contact_placements(point_scene.model, point_scene.chains, held)
    for chain in point_scene.chains:
        grip, tip = (data.oMf[point_scene.frame_id(f)] for f in (chain.gripper_frame, chain.point_frame))
        assert point[chain.name].homogeneous == pytest.approx(grip.actInv(tip).homogeneous, abs=1e-12)


def test_actuated_joints_lock_and_limit_from_the_config(scene, config):
    joints = actuated_joints(scene.model, config)
    assert len(joints.names) == scene.model.nv - 6  # every joint but the root is actuated (1 dof)
    for i, name in enumerate(joints.names):
        j = scene.model.getJointId(name)
        assert joints.q_index[i] == scene.model.joints[j].idx_q
        assert joints.lower[i] == scene.model.lowerPositionLimit[joints.q_index[i]]
    assert {n for n, held in zip(joints.names, joints.locked, strict=True) if held} == set(config.locked_joints)
    for name, value in config.locked_joints.items():
        assert joints.locked_values[joints.index(name, "")] == value
    i = joints.index("arm_left_4_joint", "")
    outside = dict(config.locked_joints, arm_left_4_joint=float(joints.upper[i]) + 0.1)
    with pytest.raises(ConfigError, match=r"^robot\.locked_joints\.arm_left_4_joint: .* rad is outside \["):
        actuated_joints(scene.model, dataclasses.replace(config, locked_joints=outside))
    faster = actuated_joints(scene.model, dataclasses.replace(config, velocity_limits={"arm_left_4_joint": 9.0}))
    assert faster.velocity_limit[i] == 9.0 and joints.velocity_limit[i] == scene.model.velocityLimit[joints.v_index[i]]


def test_a_joint_of_reversed_limits_or_of_two_values_is_refused(scene, config):
    """Either made numpy's uniform draw or the placo solver fail later (a traceback, or no posture found)."""
    model = pin.Model(scene.model)
    i = model.joints[model.getJointId("arm_left_4_joint")].idx_q
    model.lowerPositionLimit[i], model.upperPositionLimit[i] = 0.5, -0.5
    with pytest.raises(ConfigError, match=r"^robot: joint 'arm_left_4_joint': its lower limit 0.5 is above its upper"):
        actuated_joints(model, config)
    free = pin.buildModelFromXML(
        '<robot name="r"><link name="a"/><link name="b"/><joint name="spin" type="continuous"><parent link="a"/>'
        '<child link="b"/><axis xyz="0 0 1"/></joint></robot>',
        pin.JointModelFreeFlyer(),
    )
    with pytest.raises(ConfigError, match=r"^robot: joint 'spin' is a JointModelRUBZ \(2 values\): posegen plans"):
        actuated_joints(free, config)


def test_a_locked_joint_narrower_than_the_margins_keeps_none_and_a_free_one_is_refused(config):
    """A gripper's finger of 2 cm locked at 0: both margins of 0.02 crossed, and the draw failed (a traceback)."""
    names, lower, upper = ("finger", "elbow"), np.array([0.0, -2.0]), np.array([0.02, 0.0])
    config = dataclasses.replace(config, margins=dataclasses.replace(config.margins, joint_limit_rad_by_joint={}))
    margin = config.margins.joint_limit_rad
    kept = limit_margins(names, lower, upper, config, np.array([True, False]))
    assert list(kept) == [0.0, margin]
    with pytest.raises(ConfigError, match=r"leaves no room for joint 'finger' in \[0.000, 0.020\]: lock it"):
        limit_margins(names, lower, upper, config, np.array([False, False]))


def test_velocity_limits_fill_locked_joints_and_name_free_ones_without():
    urdf = np.array([1.0, 0.0, 2.0, 0.0])
    names, locked = ("a", "b", "c", "d"), np.array([False, True, False, False])
    limit = velocity_limits(urdf, names, locked, {"d": 0.5})
    assert list(limit) == [1.0, 2.0, 2.0, 0.5]  # b: locked, given the largest free limit; d: overridden
    assert list(urdf) == [1.0, 0.0, 2.0, 0.0]  # the caller's array untouched
    with pytest.raises(ConfigError, match=r"^robot\.velocity_limits_rad_s: .*\(0 rad/s\) for d; "):
        velocity_limits(urdf, names, locked, {})
    with pytest.raises(ConfigError, match=r"unknown joint 'e'.*\(robot\.velocity_limits_rad_s\)$"):
        velocity_limits(urdf, names, locked, {"e": 1.0})


def test_reference_configuration_applies_the_overrides_to_the_state(scene, config):
    joints = actuated_joints(scene.model, config)
    state = np.array(scene.model.referenceConfigurations[config.stance.reference_posture])
    assert reference_configuration(scene.model, config.stance, joints) == pytest.approx(state)
    i = joints.index("arm_left_4_joint", "")
    turned = dataclasses.replace(config.stance, reference_joints={"arm_left_4_joint": -1.0}, root_rpy_deg=(0, 0, 90))
    q = reference_configuration(scene.model, turned, joints)
    assert q[joints.q_index[i]] == -1.0
    assert pin.Quaternion(q[6], *q[3:6]).matrix() == pytest.approx(pin.rpy.rpyToMatrix(0, 0, np.pi / 2), abs=1e-12)
    unknown = dataclasses.replace(config.stance, reference_posture="half_siting")
    with pytest.raises(ConfigError, match=r"did you mean half_sitting.*\(stance\.reference_posture\)$"):
        reference_configuration(scene.model, unknown, joints)


def test_read_srdf_states_reads_the_states_and_rejects_a_binary_srdf(declared, point_config, tmp_path):
    _, model = apply_additions(declared, point_config)
    assert not model.referenceConfigurations
    read_srdf_states(model, declared.files)
    assert "half_sitting" in {str(e.key()) for e in model.referenceConfigurations}
    binary = tmp_path / "robot.srdf"
    binary.write_bytes(b"\x00\xff\xfe" * 10)
    with pytest.raises(ConfigError, match=str(binary)):
        read_srdf_states(model, dataclasses.replace(declared.files, srdf=binary))


def test_stand_puts_the_soles_flat_on_the_floor_inside_the_support_polygon(scene, config):
    reference = scene.model_configuration(scene.reference)
    reference[2] += 0.3  # raised and turned: the soles are flattened on the floor all the same
    reference[3:7] = pin.Quaternion(pin.rpy.rpyToMatrix(0.0, 0.0, 0.4)).coeffs()
    soles, polygon = stand(scene.model, config.stance, reference)
    assert list(soles) == list(config.stance.sole_frames)
    x = (polygon[:, 0] - polygon[:, 0].mean(), polygon[:, 1] - polygon[:, 1].mean())
    assert np.sum(x[0] * np.roll(x[1], -1) - np.roll(x[0], -1) * x[1]) < 0  # clockwise: negative signed area
    for pose in soles.values():
        assert pose[2, 3] == 0.0 and pose[:3, 2] == pytest.approx([0, 0, 1])
        for corner in ((x, y) for x in config.stance.foot_x_m for y in config.stance.foot_y_m):
            assert polygon_margin(polygon, (pose @ [*corner, 0.0, 1.0])[:2]) > -1e-9  # every corner within
    data = scene.model.createData()
    pin.framesForwardKinematics(scene.model, data, reference)
    yaw = [np.arctan2(*data.oMf[scene.frame_id(f)].rotation[1::-1, 0]) for f in soles]
    assert [np.arctan2(*p[1::-1, 0]) for p in soles.values()] == pytest.approx(yaw, abs=1e-9)


def test_table_pose_and_spots_follow_the_table_config(config):
    table = dataclasses.replace(config.table, yaw_deg=30.0)
    pose = table_pose(table)
    assert pose[:3, 3] == pytest.approx(table.top_center_m)
    assert pose[:3, 0] == pytest.approx([np.cos(np.pi / 6), np.sin(np.pi / 6), 0.0])
    spots = table_spots(table, config.chains)
    assert len(spots) == len(table.spots_x_m) * len(table.spots_y_m) == len({s.name for s in spots})
    assert [s.xy_table_m for s in spots] == [(x, y) for x in table.spots_x_m for y in table.spots_y_m]
    for spot in spots:
        low_high = {c.name: c.spot_y_range_m for c in config.chains}
        assert set(spot.chains) == {n for n, (lo, hi) in low_high.items() if lo <= spot.xy_table_m[1] <= hi}


def test_the_steps_compose_into_the_scene(scene, config):
    built = Scene.from_config(config)
    description = load_description(config)
    check_names(description.model, config)
    urdf_xml, model = apply_additions(description, config)
    assert urdf_xml == built.urdf_xml == scene.urdf_xml
    joints = actuated_joints(model, config)
    assert joints.names == built.joint_names and np.array_equal(joints.velocity_limit, built.velocity_limit)
    read_srdf_states(model, description.files)
    reference = reference_configuration(model, config.stance, joints)
    assert np.array_equal(reference[joints.q_index], built.reference)
    soles, polygon = stand(model, config.stance, reference)
    assert np.array_equal(polygon, built.support_polygon) and soles.keys() == built.sole_poses.keys()
    assert table_spots(config.table, config.chains) == built.spots
