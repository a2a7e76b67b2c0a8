"""An MJCF joint's ``ref`` and a slide's range through class defaults; the converted URDF's zero at MuJoCo's."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from posegen.draft.mjcf import convert_mjcf
from posegen.draft.mjcf_joints import body_joints
from posegen.errors import ConfigError
from tests.draft.humanoid_mjcf import humanoid_mjcf

RNG_SEED = 11
DEFAULTS = """<default>
    <joint damping="1"/>
    <default class="limb"><joint ref="0.2"/>
      <default class="bent"><joint ref="0.4" armature="0.1"/></default>
    </default>
  </default>"""


def _parse(body: str, compiler: str = "") -> ET.Element:
    return ET.fromstring(f"<mujoco>{compiler}{DEFAULTS}<worldbody>{body}</worldbody></mujoco>")


def _refs(root: ET.Element) -> dict[str, list[float]]:
    return {body: [j.ref for j in joints] for body, joints in body_joints(root, Path("robot.xml")).items()}


def test_a_ref_comes_from_the_joint_its_class_the_nearest_childclass_or_main():
    body = """<body name="trunk" childclass="limb">
        <joint name="own" ref="30"/><joint name="classed" class="bent"/><joint name="inherited"/>
        <body name="arm"><joint name="deeper"/>
          <body name="hand" childclass="main"><joint name="main"/><joint type="slide" ref="0.05"/></body>
        </body>
      </body>"""
    refs = _refs(_parse(body))  # degrees: MuJoCo's default unit
    assert refs["trunk"] == pytest.approx([math.radians(30), math.radians(0.4), math.radians(0.2)], abs=1e-15)
    assert refs["arm"] == pytest.approx([math.radians(0.2)], abs=1e-15)
    assert refs["hand"] == [0.0, 0.05]  # a slide's ref is a length, whatever the angle unit
    radians = _refs(_parse(body, '<compiler angle="radian"/>'))
    assert radians["trunk"] == [30.0, 0.4, 0.2]


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ('<body><joint ref="0.3"/></body>', r"robot\.xml: a body with a joint whose ref is not 0 has no name"),
        ('<body name="b"><joint class="none"/></body>', r"robot\.xml: joint class 'none' has no <default"),
    ],
)
def test_a_ref_that_cannot_be_placed_is_one_line(body, message):
    with pytest.raises(ConfigError, match=message):
        body_joints(_parse(body), Path("robot.xml"))
    assert body_joints(_parse('<body><joint ref="0"/></body>'), Path("robot.xml")) == {}  # no ref: no name needed


def test_a_slides_range_is_a_length_whatever_the_angle_unit():
    """pinocchio reads a slide's range as an angle: "-0.1 0.2" under degrees became -1.7 mm, 3.5 mm."""
    body = '<body name="b"><joint type="slide" range="-0.1 0.2"/><joint range="-10 20"/><joint type="slide"/></body>'
    joints = body_joints(_parse(body), Path("robot.xml"))["b"]
    assert [j.slide_range_m for j in joints] == [(-0.1, 0.2), None, None]  # a hinge's range is pinocchio's to read
    assert [j.name for j in joints] == ["b_joint0", "b_joint1", "b_joint2"]


def _with_refs(folder: Path) -> Path:
    """The fixture with refs: by class (knees, a hip of a three-hinge body), on a joint, on a tilted long axis."""
    path = humanoid_mjcf(folder)
    text = path.read_text().replace('<compiler angle="radian"/>', '<compiler angle="radian"/>' + DEFAULTS)
    text = text.replace('<joint name="l_knee"', '<joint class="bent" name="l_knee"')
    shank = '<body name="r_shank" pos="0 0 -0.4"'
    text = text.replace(shank + ">", shank + ' childclass="limb">')
    text = text.replace('<joint name="l_hip_roll"', '<joint ref="-0.3" name="l_hip_roll"')
    text = text.replace('<joint name="r_elbow" axis="0 1 0"', '<joint name="r_elbow" ref="-0.7" axis="0 2 1"')
    text = text.replace('<joint name="waist"', '<joint name="waist" ref="0.25"')
    path.write_text(text)
    return path


def test_the_urdf_puts_every_body_where_mujoco_does_at_the_same_joint_values(tmp_path):
    """pinocchio's zero is the pose as written (MuJoCo's ``qpos = ref``): the URDF's is MuJoCo's ``qpos = 0``."""
    mujoco = pytest.importorskip("mujoco")
    path = _with_refs(tmp_path)
    native = mujoco.MjModel.from_xml_path(str(path))
    assert np.count_nonzero(native.qpos0[7:]) == 7  # the refs above (r_shank's class reaches its foot's two)
    urdf_path = tmp_path / "robot.urdf"
    urdf_path.write_text(convert_mjcf(path).text)
    urdf = pin.buildModelFromUrdf(str(urdf_path), pin.JointModelFreeFlyer())
    data, placed = mujoco.MjData(native), urdf.createData()
    hinges = [j for j in range(native.njnt) if native.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE]
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(5):
        data.qpos[:] = native.qpos0
        q = pin.neutral(urdf)
        for j in hinges:
            name = mujoco.mj_id2name(native, mujoco.mjtObj.mjOBJ_JOINT, j)
            low, high = native.jnt_range[j]
            index = urdf.joints[urdf.getJointId(name)].idx_q
            assert (urdf.lowerPositionLimit[index], urdf.upperPositionLimit[index]) == (low, high), name
            data.qpos[native.jnt_qposadr[j]] = q[index] = rng.uniform(low, high)
        mujoco.mj_kinematics(native, data)
        q[:3], q[3:7] = data.xpos[1], np.roll(data.xquat[1], -1)  # the root where MuJoCo has it, (x, y, z, w)
        pin.framesForwardKinematics(urdf, placed, q)
        for b in range(1, native.nbody):
            name = mujoco.mj_id2name(native, mujoco.mjtObj.mjOBJ_BODY, b)
            frame = placed.oMf[urdf.getFrameId(name)]
            assert np.abs(frame.translation - data.xpos[b]).max() < 1e-9, name
            assert np.abs(frame.rotation - data.xmat[b].reshape(3, 3)).max() < 1e-9, name
