"""Simulated contacts: the true robot stands on both soles and touches the true table."""

import copy
import dataclasses

import numpy as np
import pytest

from posegen.calibrate import Perturbation, Settings, calibrate, simulate
from posegen.calibrate.simulation import contact_offsets, floor_constants
from posegen.model import Contacts, Kind, planned_kinds


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


CONTACT_NOISE = Perturbation(contact_noise_m=3e-3, contact_noise_rad=float(np.deg2rad(0.3)))


def test_contact_noise_settles_each_contact_on_its_own_local_plane(scene, example_pool):
    rows = list(range(40))
    plan = planned(example_pool, rows)
    recorded, model, x = simulate(scene, plan, CONTACT_NOISE, seed=5)
    assert len(recorded) == len(plan)
    offsets = contact_offsets(plan, CONTACT_NOISE, seed=5)
    # the recorded joints carry the noise: flush with the local planes, off the true table by the offsets
    assert np.abs(model.evaluate(x, model.observations(recorded)).contact - offsets).max() < 1e-9
    assert np.std(offsets[:, 0]) == pytest.approx(3e-3, rel=0.3)
    assert np.std(offsets[:, 1:]) == pytest.approx(np.deg2rad(0.3), rel=0.3)
    again = contact_offsets(planned(example_pool, rows[::-1]), CONTACT_NOISE, seed=5)
    assert np.array_equal(again, offsets[::-1])  # a posture's local plane, whatever plan holds it
    assert not np.allclose(contact_offsets(plan, CONTACT_NOISE, seed=6), offsets)
    # without contact noise, the robot, the table and the encoders are those of before, to the bit
    clean, _, x_clean = simulate(scene, plan, Perturbation(), seed=5)
    assert np.array_equal(x_clean, x) and not np.any(contact_offsets(plan, Perturbation(), seed=5))
    assert np.abs(model.evaluate(x, model.observations(clean)).contact).max() < 1e-9


def test_point_contacts_get_only_a_height_offset(point_scene, example_pool):
    plan = planned(example_pool, list(range(6)))
    plan = Contacts(plan.joints, plan.chains, plan.sessions, plan.labels, planned_kinds(point_scene, plan.chains))
    offsets = contact_offsets(plan, CONTACT_NOISE, seed=1)
    assert np.all(offsets[:, 0] != 0.0) and not np.any(offsets[:, 1:])


def test_the_calibration_recovers_the_contact_noise(scene, example_pool):
    """The noise a calibration reports on a simulated run is the contact noise simulated, not the encoders'."""
    rows = [i for i, p in enumerate(example_pool.postures) if p.chain == "left"][:70]
    spots = tuple(example_pool.postures[i].spot for i in rows)  # the table regions of the grouped CV
    plan = Contacts(example_pool.joints()[rows], ("left",) * len(rows), ("sim",) * len(rows), spots)
    perturbation = dataclasses.replace(CONTACT_NOISE, encoder_noise_rad=float(np.deg2rad(0.005)))
    recorded, _, _ = simulate(scene, plan, perturbation, seed=7)
    calibration = calibrate(scene, recorded, ["sim"], Settings(candidates=("full",), fold_seeds=1))
    height, roll, pitch = calibration.after.noise.contact
    assert height == pytest.approx(3e-3, rel=0.3)
    assert roll == pytest.approx(np.deg2rad(0.3), rel=0.3) and pitch == pytest.approx(np.deg2rad(0.3), rel=0.3)


def test_the_true_robot_keeps_its_planned_postures(scene, example_pool):
    """Every posture of the example pool, 3 mm and 0.5 deg errors: all kept, flush, standing, within the limits.

    Before issue 32, 15-18 of these 200 were left out (the second leg's closure stalled, or a
    joint went past its limit): a few millimetres cannot put a bent-knee stance out of reach.
    """
    from posegen.model import LIMIT_TOLERANCE_RAD

    plan = planned(example_pool, list(range(len(example_pool.postures))))
    recorded, model, x = simulate(scene, plan, Perturbation(length_m=3e-3), seed=8)
    assert len(recorded) == len(plan)
    truth = model.evaluate(x, model.observations(recorded))
    assert np.abs(truth.contact).max() < 1e-9 and np.abs(truth.floor).max() < 1e-9
    assert np.all(recorded.joints >= scene.lower - LIMIT_TOLERANCE_RAD - 1e-12)
    assert np.all(recorded.joints <= scene.upper + LIMIT_TOLERANCE_RAD + 1e-12)


def test_a_second_leg_that_cannot_close_alone_closes_with_both_legs(scene, example_pool):
    """A true second shank 5 cm short under the three least bent second knees of the pool's first twenty postures.

    The second leg alone cannot reach the floor (before issue 32 these were left out); both
    legs do: the anchor leg bends, the pelvis moves, and every residual closes.
    """
    from posegen.calibrate.simulation import perturbed_robot, settle_true

    second, anchor = scene.leg_joints(scene.second_sole), scene.leg_joints(scene.anchor_sole)
    knee = scene.joint_names[second[2]]
    rows = [int(i) for i in np.argsort(example_pool.joints()[:20, second[2]])[:3]]  # bent >= the knee's own margin
    plan = planned(example_pool, rows)
    exact = Perturbation(length_m=0.0, angle_rad=0.0)
    model, x = perturbed_robot(scene, ("left", "right"), plan.sessions, exact, 1)  # both legs: the floor closes
    x[model.contact.column(next(p for p in model.contact.parameters if p.owner == knee and p.field == "pz"))] += 0.05
    settled, converged, residual = settle_true(model, x, plan)
    assert np.all(converged) and np.abs(residual).max() < 1e-9
    moved = np.abs(settled.joints[:, anchor] - plan.joints[:, anchor]).max(axis=1)
    assert np.all(moved > 1e-3)  # the anchor leg bent: the second one alone could not close the floor


def test_a_joint_stops_at_its_limit_and_the_others_settle(scene, example_pool):
    """Limits drawn in around a posture's planned angles: the settled joints stay inside, and it still settles."""
    from posegen.calibrate.simulation import perturbed_robot, settle_true
    from posegen.model import LIMIT_TOLERANCE_RAD

    plan = planned(example_pool, [0])
    model, x = perturbed_robot(scene, plan.chains, plan.sessions, Perturbation(), 3)
    free, _, _ = settle_true(model, x, plan)
    pushed = int(np.argmax(np.abs(free.joints[0] - plan.joints[0])))  # the joint the settle moves most
    tight = copy.copy(scene)  # the same robot, this joint's limit at its planned angle (tolerance included)
    tight.lower, tight.upper = scene.lower.copy(), scene.upper.copy()
    bound = plan.joints[0, pushed]
    if free.joints[0, pushed] > bound:
        tight.upper[pushed] = bound - LIMIT_TOLERANCE_RAD
    else:
        tight.lower[pushed] = bound + LIMIT_TOLERANCE_RAD
    model.scene = tight
    held, converged, residual = settle_true(model, x, plan)
    assert converged[0] and np.abs(residual).max() < 1e-9
    assert held.joints[0, pushed] == pytest.approx(bound, abs=1e-12)  # stopped where the plan put it, at its limit
    assert not np.allclose(held.joints[0], free.joints[0])  # the others settled instead


def test_a_posture_left_out_says_why(scene):
    from posegen.calibrate.simulation import left_out_reason

    joints = scene.reference.copy()
    floor = left_out_reason(scene, joints, np.array([1e-12, 0, 0, 0, 0, 3.2e-3, 0, 0, 0]))
    assert floor.startswith("the second sole stays 3.20 mm, 0.00 deg off the floor")
    contact = left_out_reason(scene, joints, np.array([2e-3, 1e-3, 0, 0, 0, 0, 0, 0, 0]))
    assert contact.startswith("the contact stays 2.00 mm, 0.06 deg off its table")
    joints[4] = scene.upper[4] + 0.3
    assert left_out_reason(scene, joints, np.zeros(9)) == f"joint {scene.joint_names[4]} past its limit by 0.3000 rad"


@pytest.mark.parametrize(("x", "y", "yaw"), [(0.0, -0.2, 0.0), (0.03, 0.19, 0.1), (-0.01, 0.2, 3.0), (0.0, 0.2, -2.5)])
def test_the_floor_constants_are_the_second_sole_s_place_and_yaw(x, y, yaw):
    relative = np.eye(4)  # the second sole in the anchor's frame: turned by yaw about z, then placed
    relative[:2, :2] = [[np.cos(yaw), -np.sin(yaw)], [np.sin(yaw), np.cos(yaw)]]
    relative[:2, 3] = x, y
    np.testing.assert_allclose(floor_constants(relative), (x, y, yaw), atol=1e-15)
