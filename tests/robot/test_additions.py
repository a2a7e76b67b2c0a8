"""What a config adds to a robot description: read, applied at load, and checked."""

import copy
import dataclasses

import numpy as np
import pinocchio as pin
import pytest
import yaml

from posegen.errors import ConfigError
from posegen.robot import Scene, check_for_planning, load_config, parse_config
from tests.conftest import CONFIG, ROOT

ROMEO = ROOT / "configs" / "romeo_table.yaml"
ICUB = ROOT / "configs" / "icub_table.yaml"


def raw(path=CONFIG):
    return yaml.safe_load(path.read_text())


def test_additions_round_trip():
    data = raw(ICUB)
    data["stance"]["reference_joints"]["torso_yaw"] = 0.1
    config = parse_config(data)
    assert config.frames and config.velocity_limits and config.collision.disabled_pairs and config.collision.shapes
    assert parse_config(config.to_dict()).to_dict() == config.to_dict()


def test_a_config_without_additions_saves_as_before(config):
    robot = config.to_dict()["robot"]
    assert set(robot) == {"source", "locked_joints"} and "reference_joints" not in config.to_dict()["stance"]


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d["robot"].update(velocity_limit={"a": 1}), r"^robot: unknown keys \['velocity_limit'\]"),
        (lambda d: d["robot"].update(velocity_limits_rad_s={"arm_left_1_joint": 0}), "must be > 0 rad/s"),
        (lambda d: d["robot"].update(collision={"disabled_pairs": [["a", "b", "never"]]}), "unknown reason 'never'"),
        (lambda d: d["robot"].update(collision={"disabled_pairs": [["a", "a"]]}), r"\[0\]: 'a' paired with itself"),
        (lambda d: d["robot"].update(collision={"shapes": {"x": [{"cone": {}}]}}), r"expected \{capsule"),
        (lambda d: d["robot"].update(frames={"tip": {"parent": "a", "xyz": [0, 0, 0]}}), r"unknown keys \['xyz'\]"),
    ],
)
def test_malformed_additions_name_their_field(edit, message):
    data = raw()
    edit(data)
    with pytest.raises(ConfigError, match=message):
        parse_config(data)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d["robot"].update(frames={"tip": {"parent": "no_link", "xyz_m": [0, 0, 0]}}), "unknown link"),
        (lambda d: d["robot"].update(frames={"base_link": {"parent": "torso_2_link", "xyz_m": [0, 0, 0]}}), "has a"),
        (lambda d: d["robot"].update(velocity_limits_rad_s={"neck_joint": 1.0}), r"unknown joint 'neck_joint'.*rad_s"),
        (lambda d: d["robot"].update(collision={"disabled_pairs": [["base_link", "hat"]]}), r"unknown link 'hat'"),
        (lambda d: d["stance"].update(reference_joints={"knee": 0.1}), r"unknown joint 'knee'.*reference_joints"),
        (lambda d: _stand_on(d, "leg_left_3_link", "leg_right_3_link"), "is not under the robot"),
        (lambda d: d["stance"].update(reference_joints={"leg_left_4_joint": 1.2}), "not on one floor"),
        (lambda d: d["table"].update(top_center_m=[0.65, 0.0, 2.5]), r"^table\.top_center_m: out of reach"),
    ],
)
def test_bad_names_and_stances_are_one_line_errors(edit, message):
    """Names fail when the scene is built; stance and reach before planning."""
    data = copy.deepcopy(raw())
    edit(data)
    with pytest.raises(ConfigError, match=message) as err:
        check_for_planning(Scene(parse_config(data)))
    assert "\n" not in str(err.value)


def test_an_unbalanced_reference_names_the_field():
    data = raw()
    data["margins"]["com_m"] = 0.2  # wider than the feet allow: no posture is balanced enough
    with pytest.raises(ConfigError, match=r"^stance\.reference_posture: 'half_sitting' is not balanced"):
        check_for_planning(Scene(parse_config(data)))


def test_declared_frame_sits_where_declared(scene):
    data = raw()
    probe = {"parent": "arm_left_7_link", "xyz_m": [0.01, -0.02, 0.03], "rpy_deg": [0, 90, 0]}
    data["robot"]["frames"] = {"probe": probe}
    declared = Scene(parse_config(data))
    q = declared.configuration(declared.reference)
    d = declared.model.createData()
    pin.framesForwardKinematics(declared.model, d, q)
    placement = d.oMf[declared.frame_id("arm_left_7_link")].actInv(d.oMf[declared.frame_id("probe")])
    assert placement.translation == pytest.approx([0.01, -0.02, 0.03], abs=1e-12)
    assert placement.rotation == pytest.approx(pin.rpy.rpyToMatrix(0, np.pi / 2, 0), abs=1e-12)
    assert declared.joint_names == scene.joint_names  # a frame adds no joint


def test_reference_joints_override_the_srdf_state(scene):
    data = raw()
    data["stance"]["reference_joints"] = {"arm_left_4_joint": -1.0}
    moved = Scene(parse_config(data))
    i = scene.joint_index("arm_left_4_joint")
    assert moved.reference[i] == -1.0
    others = np.arange(len(scene.joint_names)) != i
    assert moved.reference[others] == pytest.approx(scene.reference[others])


def test_velocity_limits_override_and_missing_ones_are_named():
    config = load_config(ROMEO)
    scene = Scene(config)
    finger = scene.joint_index("LFinger21")
    assert scene.velocity_limit[finger] > 0  # 0 in the URDF, locked: never binds
    shoulder = scene.joint_index("LShoulderPitch")
    faster = dataclasses.replace(config, velocity_limits={"LShoulderPitch": 9.0})
    assert Scene(faster).velocity_limit[shoulder] == 9.0
    locked = {k: v for k, v in config.locked_joints.items() if k != "LFinger21"}
    with pytest.raises(ConfigError, match=r"^robot\.velocity_limits_rad_s: .*no velocity limit.*LFinger21"):
        Scene(dataclasses.replace(config, locked_joints=locked))


def test_example_robot_data_names_and_srdf():
    config = load_config(ROMEO)
    no_srdf = dataclasses.replace(config, robot=dataclasses.replace(config.robot, srdf=None))
    with pytest.raises(ConfigError, match=r"^stance\.reference_posture: 'half_sitting' .* no SRDF; .*reference_joints"):
        Scene(no_srdf)  # the loader has none: nothing to read the state from
    standing = dataclasses.replace(no_srdf, stance=dataclasses.replace(config.stance, reference_posture=""))
    assert Scene(standing).files.srdf is None  # no SRDF needed otherwise
    unknown = dataclasses.replace(config, robot=dataclasses.replace(config.robot, example_robot_data="talosfull"))
    with pytest.raises(ConfigError, match=r"unknown example-robot-data robot 'talosfull'; .*; did you mean talos_full"):
        Scene(unknown)


def _stand_on(data, left, right):
    """The stance and both chains on these two frames."""
    data["stance"]["sole_frames"] = [left, right]
    data["chains"]["left"]["sole_frame"], data["chains"]["right"]["sole_frame"] = left, right
