"""The force/torque sensors read the wrench the far side puts on them: pinocchio's inverse dynamics
(RNEA) of the same robot, the sensor's fixed joint made a joint of its own, at a still posture."""

from __future__ import annotations

import re

import mujoco
import numpy as np
import pinocchio as pin

from posegen.physics.builder import Built
from posegen.physics.sensors import SensorNoise, Sensors, sensor_wrench
from posegen.physics.tool import Tool
from posegen.robot import Scene


def _with_sensor_joint(urdf: str, link: str) -> str:
    """The URDF with the fixed joint above ``link`` made a revolute joint (pinocchio keeps its body apart)."""
    pattern = re.compile(
        r'<joint name="([^"]+)" type="fixed">(\s*<parent link="[^"]+"\s*/>\s*<child link="' + link + r'"\s*/>)'
    )
    found = pattern.search(urdf)
    assert found, link
    return urdf.replace(
        found.group(0),
        f'<joint name="{found.group(1)}" type="revolute"><axis xyz="0 0 1"/>'
        f'<limit lower="-1" upper="1" effort="1" velocity="1"/>{found.group(2)}',
    )


def test_wrist_sensors_read_the_rnea_wrench_at_rest(scene: Scene, nominal: Built, tools: dict[str, Tool]) -> None:
    rng = np.random.default_rng(4)
    joints = scene.reference + rng.normal(0.0, 0.2, len(scene.joint_names))
    joints = np.clip(joints, scene.lower, scene.upper)
    model, layout = nominal.model, nominal.layout
    data = mujoco.MjData(model)
    q = scene.configuration(joints)
    q[2] += 2.0  # in the air, clear of the floor and the table: gravity alone
    data.qpos[:3], data.qpos[3:7] = q[:3], q[[6, 3, 4, 5]]
    data.qpos[layout.qpos] = joints
    data.qvel[:], data.qacc[:] = 0.0, 0.0
    mujoco.mj_inverse(model, data)  # still: the sensors read the static wrenches
    assert data.ncon == 0
    for chain in scene.chains:
        tool = tools[chain.name]
        pmodel = pin.buildModelFromXML(_with_sensor_joint(scene.urdf_xml, tool.link), pin.JointModelFreeFlyer())
        pdata = pmodel.createData()
        pq = pin.neutral(pmodel)
        for name, value in zip(scene.joint_names, joints, strict=True):
            pq[pmodel.joints[pmodel.getJointId(name)].idx_q] = value
        pq[:7] = q[:7]
        pin.rnea(pmodel, pdata, pq, np.zeros(pmodel.nv), np.zeros(pmodel.nv))
        parent_on_tool = pdata.f[pmodel.getJointId(_joint_of(pmodel, tool.link))]  # in the sensor link's frame
        expected = -np.concatenate([parent_on_tool.linear, parent_on_tool.angular])  # the tool's wrench on the sensor
        reading = sensor_wrench(data, layout.wrists[chain.name])
        assert np.abs(reading - expected).max() < 1e-6, (chain.name, reading, expected)
        assert abs(np.linalg.norm(reading[:3]) - 9.81 * tool.mass_kg) < 1e-6  # its weight, in its frame


def _joint_of(model: pin.Model, link: str) -> str:
    return str(model.names[model.frames[model.getFrameId(link)].parentJoint])


def test_sole_sensors_carry_the_robot_and_wrist_readings_are_noisy_and_offset(scene: Scene, nominal: Built) -> None:
    model, layout = nominal.model, nominal.layout
    data = mujoco.MjData(model)
    q = scene.configuration(scene.reference)
    data.qpos[:3], data.qpos[3:7] = q[:3], q[[6, 3, 4, 5]]
    data.qpos[2] -= 1e-3  # pressed into the floor
    data.qpos[layout.qpos] = scene.reference
    mujoco.mj_inverse(model, data)
    sensors = Sensors(layout, SensorNoise(force_n=0.5, force_offset_n=3.0), seed=5)
    soles = sensors.soles(data)
    assert all(w[2] > 0 for w in soles)  # the floor pushes the soles up, in their frames
    clean = {c: sensor_wrench(data, s) for c, s in layout.wrists.items()}
    readings = [sensors.wrists(data) for _ in range(200)]
    for chain, expected in clean.items():
        samples = np.array([r[chain] for r in readings])
        assert np.abs(samples.mean(axis=0) - expected - sensors.offsets[chain]).max() < 0.15
        assert 0.4 < samples[:, :3].std(axis=0).mean() < 0.6
