"""The tool's weight on a wrist sensor: fitted from a recording with contacts, removed, or refused."""

import numpy as np
import pinocchio as pin
import pytest

from posegen.calibrate.tool_gravity import fit_tool_gravity, sensor_gravity

MASS_KG, COM_M = 1.4, np.array([0.01, -0.02, -0.07])


@pytest.fixture(scope="module")
def recording(scene):
    """A wrist turning through a slow random motion; 30 N contacts during a quarter of the samples."""
    rng = np.random.default_rng(4)
    times = np.linspace(0.0, 60.0, 3001)
    arm = [scene.joint_index(f"arm_left_{k}_joint") for k in range(1, 8)]
    joints = np.tile(scene.reference, (len(times), 1))
    for j in arm:
        phase, period = rng.uniform(0, 2 * np.pi), rng.uniform(8.0, 20.0)
        joints[:, j] += 0.5 * np.sin(2 * np.pi * times / period + phase)
    joints = np.clip(joints, scene.lower, scene.upper)
    gravity = sensor_gravity(scene, "left", times, joints, times)
    offset = np.array([3.0, -2.0, 5.0, 0.1, -0.2, 0.05])
    weight = np.hstack([MASS_KG * gravity, MASS_KG * np.cross(COM_M, gravity)])  # the tool on the sensor
    contact = (np.sin(2 * np.pi * times / 6.0) > 0.7).astype(float)  # 25 % of the time
    pushed = np.zeros((len(times), 6))
    pushed[:, 2] = -30.0 * contact
    noise = rng.normal(0.0, 1.0, (len(times), 6)) * [0.3, 0.3, 0.3, 0.03, 0.03, 0.03]  # N, N m
    wrench = weight + offset + pushed + noise
    return times, joints, gravity, wrench, contact, offset


def test_gravity_in_the_sensor_frame_is_the_world_gravity_turned(scene, recording):
    _, joints, gravity, *_ = recording
    model, data = scene.model, scene.model.createData()
    pin.framesForwardKinematics(model, data, scene.configuration(joints[1234]))
    rotation = data.oMf[scene.frame_id("wrist_left_ft_link")].rotation
    # interpolated from 50 Hz: within the motion's change over 10 ms
    assert gravity[1234] == pytest.approx(rotation.T @ [0.0, 0.0, -9.81], abs=2e-2)
    assert np.linalg.norm(gravity, axis=1) == pytest.approx(9.81, abs=2e-2)


def test_mass_com_and_offset_recovered_and_contacts_stand_out(scene, recording):
    _, _, gravity, wrench, contact, offset = recording
    tool = fit_tool_gravity(scene, "left", gravity, wrench[:, :3], wrench[:, 3:], threshold_n=15.0)
    assert tool.fitted
    assert tool.mass_kg == pytest.approx(MASS_KG, rel=0.02)
    assert tool.com_distance_m == pytest.approx(np.linalg.norm(COM_M), rel=0.05)
    assert tool.offset == pytest.approx(offset, abs=0.1)
    assert tool.free_fraction == pytest.approx(1 - contact.mean(), abs=0.02)
    force = np.linalg.norm(tool.residual(gravity, wrench[:, :3], wrench[:, 3:])[:, :3], axis=1)
    assert np.all((force > 15.0) == contact.astype(bool))
    # the offset alone (what measure did before) misreads the turning weight
    median = np.linalg.norm(wrench[:, :3] - np.median(wrench[:, :3], axis=0), axis=1)
    assert np.max(median[contact == 0]) > 8.0


def test_a_wrist_that_does_not_turn_keeps_the_offset_and_says_so(scene, recording):
    _, _, gravity, wrench, _, _ = recording
    still = np.tile(gravity[0], (len(gravity), 1))
    tool = fit_tool_gravity(scene, "left", still, wrench[:, :3], wrench[:, 3:], threshold_n=15.0)
    assert not tool.fitted
    assert "hardly turned" in tool.note
    assert tool.offset == pytest.approx(np.median(wrench, axis=0))


def test_a_configured_tool_is_used_as_given(scene, recording):
    import dataclasses

    from posegen.robot import Scene

    _, _, gravity, wrench, _, offset = recording
    chains = tuple(
        dataclasses.replace(c, tool_mass_kg=MASS_KG, tool_com_m=tuple(COM_M)) if c.name == "left" else c
        for c in scene.config.chains
    )
    configured = Scene(dataclasses.replace(scene.config, chains=chains))
    tool = fit_tool_gravity(configured, "left", gravity, wrench[:, :3], wrench[:, 3:], threshold_n=15.0)
    assert tool.mass_kg == pytest.approx(MASS_KG, rel=1e-9)
    assert "from the config" in tool.note
    assert tool.offset == pytest.approx(offset, abs=0.1)
