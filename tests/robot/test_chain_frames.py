"""What calibration needs of the chain frames, checked before any work."""

import dataclasses

import pytest

from posegen.errors import ConfigError
from posegen.robot import Scene, load_config
from posegen.robot.additions import FrameConfig
from posegen.robot.chain_frames import check_calibration_frames, declared_chain_frames
from tests.conftest import CONFIG, ROOT


def test_talos_frames_are_fixed_links_of_its_urdf():
    scene = Scene(load_config(CONFIG))
    check_calibration_frames(scene)
    assert declared_chain_frames(scene) == ()


def test_a_frame_moved_by_its_own_joint_is_refused():
    # iCub's hand link is its wrist joint's own link: a placement written back would replace the wrist's origin
    with pytest.raises(ConfigError, match=r"^chains\.left\.gripper_frame: 'l_hand' is moved by joint 'l_wrist_yaw'"):
        check_calibration_frames(Scene(load_config(ROOT / "configs" / "icub_table.yaml")))


def test_a_declared_frame_must_be_level_and_its_contacts_rigid():
    config = load_config(CONFIG)
    tilted = FrameConfig("tilted_sole", "leg_left_6_link", (0.0, 0.0, -0.107), (0.0, 20.0, 0.0))
    left = dataclasses.replace(config.chains[0], sole_frame="tilted_sole")
    scene = Scene(dataclasses.replace(config, frames=(*config.frames, tilted), chains=(left, config.chains[1])))
    assert declared_chain_frames(scene) == ("tilted_sole",)
    with pytest.raises(ConfigError, match=r"^chains\.left\.sole_frame: 'tilted_sole' is tilted 20\.0 deg"):
        check_calibration_frames(scene)
    on_finger = tuple(  # contact points on the link the gripper joint moves
        FrameConfig(f"finger_point_{k}", "gripper_left_motor_double_link", (0.01 * k, 0.02 * (k % 2), -0.05))
        for k in range(3)
    )
    left = dataclasses.replace(config.chains[0], fingertip_frames=tuple(f.name for f in on_finger))
    held = dataclasses.replace(config, frames=(*config.frames, *on_finger), chains=(left, config.chains[1]))
    check_calibration_frames(Scene(held))  # the gripper joint is locked: the points ride on the gripper
    free = {k: v for k, v in config.locked_joints.items() if k != "gripper_left_joint"}
    with pytest.raises(
        ConfigError, match=r"^chains\.left: contact frame 'finger_point_0' moves on joint\(s\) gripper_left_joint"
    ):
        check_calibration_frames(Scene(dataclasses.replace(held, locked_joints=free)))
