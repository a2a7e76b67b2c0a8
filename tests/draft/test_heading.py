"""Which way a drafted robot faces: its root's x axis, unless both knees say another (iCub's root: -x)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from posegen.draft import write_draft
from posegen.draft.covering import skeleton
from posegen.draft.heading import TURNED
from posegen.robot import Scene, load_config
from tests.draft.humanoid_urdf import humanoid_urdf
from tests.test_artefact_bytes import ICUB  # the reduced iCub of example-robot-data: its root's x axis points back


@pytest.fixture(scope="module")
def icub(tmp_path_factory):
    config = tmp_path_factory.mktemp("icub") / "icub.yaml"
    draft = write_draft(ICUB, str(config), samples=10, seed=2)
    return draft, Scene(load_config(config))


def test_a_robot_whose_knees_bend_against_its_root_x_axis_is_turned_around(icub):
    draft, scene = icub
    assert TURNED.format(axis="-x") in draft.checks
    assert [s.declared.parent for s in draft.soles] == ["l_ankle_2", "r_ankle_2"]  # left is left
    q = scene.configuration(scene.reference)
    data = scene.model.createData()
    pin.framesForwardKinematics(scene.model, data, q)
    left, right = (data.oMf[scene.frame_id(s)].translation for s in scene.stance.sole_frames)
    table = scene.table_pose[:3, 3]
    forward = np.cross(left - right, [0.0, 0.0, 1.0])  # left = up x forward, so forward = left x up
    assert (table - (left + right) / 2) @ forward > 0  # the table stands in front of it
    assert scene.table_pose[:3, 1] @ (left - right) > 0  # the table's +y side, the left hand's spots, on its left
    knee = scene.model.getJointId("l_knee")
    assert scene.model.lowerPositionLimit[scene.model.joints[knee].idx_q] < -1.5  # it flexes negative: backwards


def test_the_turned_draft_loads_and_stands_its_feet_on_the_floor(icub):
    draft, scene = icub
    assert draft.notes[-1].startswith("the draft loads as a scene"), draft.notes[-1]
    assert {"l_foot", "r_foot"} <= set(scene.stance.floor_contact_frames)  # the plates fixed to the ankles


def test_a_robot_facing_its_root_x_axis_is_not_turned(tmp_path):
    draft = write_draft(str(humanoid_urdf(tmp_path / "description", "z")), str(tmp_path / "c.yaml"), samples=5)
    assert not [c for c in draft.checks if c.startswith("the robot faces")]
    assert draft.table_yaw_deg == 0.0


def test_a_robot_facing_its_root_y_axis_is_drafted_as_the_same_robot_turned(tmp_path):
    """Before, the heading took the root's x axis (the robot's right): the table at its side, left and right swapped."""
    straight = write_draft(str(humanoid_urdf(tmp_path / "x", "z")), str(tmp_path / "x.yaml"), samples=5, seed=3)
    turned = write_draft(str(humanoid_urdf(tmp_path / "y", "zy")), str(tmp_path / "y.yaml"), samples=5, seed=3)
    assert TURNED.format(axis="+y") in turned.checks
    assert turned.table_yaw_deg == 90.0
    assert [c.joints for c in turned.chains] == [c.joints for c in straight.chains]  # the left arm is the left chain
    assert (turned.foot_x_m, turned.foot_y_m) == (straight.foot_x_m, straight.foot_y_m)
    x, y, z = straight.table_center_m
    assert turned.table_center_m == pytest.approx((-y, x, z), abs=1e-3)  # in front of it, a quarter turn round
    assert turned.spots_y_m == straight.spots_y_m


def test_a_capsule_along_the_joints_reaches_the_child_joint_not_past_it():
    model = pin.buildModelFromUrdf(ICUB, pin.JointModelFreeFlyer())
    shin = skeleton(model, "l_lower_leg")
    frame = model.frames[model.getFrameId("l_lower_leg")]
    ankle = next(c for c in range(2, model.njoints) if model.parents[c] == frame.parentJoint)
    joint_in_link = frame.placement.actInv(model.jointPlacements[ankle].translation)
    (capsule,) = shin
    reach = np.linalg.norm(np.subtract(capsule.to_m, capsule.from_m)) + capsule.radius_m
    assert reach == pytest.approx(np.linalg.norm(joint_in_link - np.array(capsule.from_m)), abs=2e-3)  # rounded to mm
