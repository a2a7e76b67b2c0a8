"""Simulated contacts: the true robot stands on both soles and touches the true table."""

import dataclasses

import numpy as np
import pytest

from posegen.calibrate import Perturbation, simulate
from posegen.model import Contacts, Kind


def planned(pool, rows, session="sim"):
    joints = pool.joints()[rows]
    return Contacts(joints, tuple(pool.postures[i].chain for i in rows), (session,) * len(rows), ("",) * len(rows))


def test_settled_contacts_are_flush_and_stand_on_the_true_robot(scene, example_pool):
    plan = planned(example_pool, list(range(20)))
    recorded, model, x = simulate(scene, plan, Perturbation(), seed=1)
    truth = model.evaluate(x, model.observations(recorded))
    assert np.abs(truth.contact).max() < 1e-9 and np.abs(truth.floor).max() < 1e-9
    nominal = model.evaluate(model.nominal(), model.observations(recorded))
    assert np.abs(nominal.contact).max() > 1e-3  # the nominal robot is off
    second_leg = scene.leg_joints(scene.second_sole)
    for i, chain in enumerate(recorded.chains):
        moving = set(model.contact.chains[chain].joint_indices) | set(second_leg)
        outside = [j for j in range(len(scene.joint_names)) if j not in moving]
        assert np.abs(recorded.joints[i, outside] - plan.joints[i, outside]).max() == 0.0
    assert (
        0 < np.abs(recorded.joints - plan.joints).max() < 0.2
    )  # a small correction, as a force-controlled contact makes


def test_errors_have_the_requested_size(scene, example_pool):
    plan = planned(example_pool, [0, 1])
    _, model, x = simulate(scene, plan, Perturbation(length_m=2e-3, angle_rad=np.deg2rad(0.5)), seed=2)
    dev = model.theta(x) - model.contact.nominal()
    params = model.contact.parameters
    lengths = [dev[i] for i, p in enumerate(params) if p.unit.value == "m" and p.group.value != "plane"]
    angles = [dev[i] for i, p in enumerate(params) if p.unit.value == "rad" and p.group.value != "plane"]
    assert np.std(lengths) == pytest.approx(2e-3, rel=0.3)
    assert np.max(np.abs(angles)) <= np.deg2rad(1.5) + 1e-12


def test_encoder_noise_is_added(scene, example_pool):
    plan = planned(example_pool, list(range(5)))
    clean, _, _ = simulate(scene, plan, Perturbation(), seed=3)
    noisy, _, _ = simulate(scene, plan, Perturbation(encoder_noise_rad=1e-3), seed=3)
    assert 1e-4 < np.std(noisy.joints - clean.joints) < 2e-3


def test_a_compliant_robot_gives_way_under_gravity(scene, example_pool):
    """With the config's compliance groups soft, the rigid truth no longer explains the recorded angles."""
    config = dataclasses.replace(
        scene.config,
        calibration=dataclasses.replace(
            scene.calibration, compliance={"hip_pitch": ("leg_left_3_joint", "leg_right_3_joint")}
        ),
    )
    soft_scene = type(scene)(config)
    plan = planned(example_pool, list(range(8)))
    perturbation = Perturbation(compliance_rad_per_nm=3e-4, compliance_groups=("hip_pitch",))
    recorded, model, x = simulate(soft_scene, plan, perturbation, seed=4)
    assert list(model.compliance) == ["hip_pitch"]  # only the groups asked for give way
    observations = model.observations(recorded)
    assert np.abs(model.evaluate(x, observations).contact).max() < 1e-9
    rigid = x.copy()
    rigid[model.columns([Kind.COMPLIANCE])] = 0.0
    assert np.abs(model.evaluate(rigid, observations).contact[:, 0]).max() > 1e-3  # mm of sag at the gripper
