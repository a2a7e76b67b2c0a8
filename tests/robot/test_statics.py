"""Gravity torques of standing postures, against statics computed another way."""

import numpy as np
import pinocchio as pin
import pytest

from posegen.robot.statics import gravity_torques


@pytest.fixture(scope="module")
def postures(scene):
    rng = np.random.default_rng(3)
    joints = np.tile(scene.reference, (3, 1))
    for name in ("arm_left_1_joint", "arm_left_2_joint", "arm_right_4_joint", "torso_2_joint"):
        j = scene.joint_index(name)
        joints[:, j] = rng.uniform(scene.lower[j], scene.upper[j], 3)
    return joints


def test_arm_torque_is_the_moment_of_the_weight_it_carries(scene, postures):
    """Above the legs the robot is a tree: a joint holds the weight of its subtree, m g x (c - p) about its axis."""
    model, data = scene.model, scene.model.createData()
    tau = gravity_torques(scene, postures)
    gravity = np.array([0.0, 0.0, -9.81])
    for posture, torque in zip(postures, tau, strict=True):
        q = scene.configuration(posture)
        pin.forwardKinematics(model, data, q)
        pin.centerOfMass(model, data, q, True)  # data.com[j], data.mass[j]: subtree of joint j, in its frame
        for name in ("arm_left_1_joint", "arm_left_2_joint", "arm_right_4_joint", "torso_2_joint"):
            jid = model.getJointId(name)
            placement = data.oMi[jid]
            axis = placement.rotation @ np.eye(3)["XYZ".index(model.joints[jid].shortname()[-1])]
            moment = np.cross(placement.act(data.com[jid]) - placement.translation, data.mass[jid] * gravity)
            assert torque[scene.joint_index(name)] == pytest.approx(-axis @ moment, abs=1e-6), name


def test_the_floor_carries_the_whole_weight(scene, postures):
    """The torques are those of sole wrenches whose vertical forces add up to m g."""
    model, data = scene.model, scene.model.createData()
    tau = gravity_torques(scene, postures)
    mass = pin.computeTotalMass(model)
    for posture, torque in zip(postures, tau, strict=True):
        q = scene.configuration(posture)
        gravity = pin.computeGeneralizedGravity(model, data, q)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        soles = [scene.frame_id(f) for f in scene.stance.sole_frames]
        contact = np.vstack([pin.getFrameJacobian(model, data, f, pin.LOCAL) for f in soles])
        full = np.zeros(model.nv)
        full[scene.velocity_indices()] = torque
        wrench = np.linalg.lstsq(contact.T, gravity - full, rcond=None)[0]
        assert contact.T @ wrench == pytest.approx(gravity - full, abs=1e-7)  # torques and wrenches balance
        vertical = sum((data.oMf[f].rotation @ wrench[6 * k : 6 * k + 3])[2] for k, f in enumerate(soles))
        assert vertical == pytest.approx(mass * 9.81, rel=1e-6)


def test_linear_torques_match_finite_differences(scene, postures):
    """Every row, legs included (the split of the weight between the feet changes too), pressing and not."""
    from posegen.robot.statics import holding_torques, linear_torques

    joints = scene.close_stance(postures[0])
    step = 1e-6
    for chain, force in ((None, 0.0), ("left", 30.0)):
        lin = linear_torques(scene, joints, chain, force)
        assert lin.torques == pytest.approx(holding_torques(scene, joints[None], [chain], force)[0], abs=1e-9)
        numeric = np.zeros_like(lin.jacobian)
        for k in range(len(joints)):
            d = np.zeros(len(joints))
            d[k] = step
            plus = holding_torques(scene, (joints + d)[None], [chain], force)[0]
            minus = holding_torques(scene, (joints - d)[None], [chain], force)[0]
            numeric[:, k] = (plus - minus) / (2 * step)
        assert np.abs(lin.jacobian - numeric).max() < 1e-5 * np.abs(numeric).max()


def test_the_table_carries_the_hand_force(scene, postures):
    """Pressing F on the hand: the torques balance the weight, F along the table normal at the hand, and sole
    wrenches whose vertical forces add up to m g - F."""
    from posegen.robot.statics import holding_torques

    model, data = scene.model, scene.model.createData()
    mass = pin.computeTotalMass(model)
    hand = scene.frame_id(scene.chain("left").contact_frame)
    for posture in postures:
        tau = holding_torques(scene, posture[None], ["left"], 30.0)[0]
        q = scene.configuration(posture)
        gravity = pin.computeGeneralizedGravity(model, data, q)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        pushed = gravity - pin.getFrameJacobian(model, data, hand, pin.LOCAL_WORLD_ALIGNED)[:3].T @ [0, 0, 30.0]
        soles = [scene.frame_id(f) for f in scene.stance.sole_frames]
        contact = np.vstack([pin.getFrameJacobian(model, data, f, pin.LOCAL) for f in soles])
        full = np.zeros(model.nv)
        full[scene.velocity_indices()] = tau
        wrench = np.linalg.lstsq(contact.T, pushed - full, rcond=None)[0]
        assert contact.T @ wrench == pytest.approx(pushed - full, abs=1e-7)
        vertical = sum((data.oMf[f].rotation @ wrench[6 * k : 6 * k + 3])[2] for k, f in enumerate(soles))
        assert vertical == pytest.approx(mass * 9.81 - 30.0, rel=1e-6)


def test_effort_ratio_names_the_worst_joint(scene, postures):
    from posegen.robot.statics import Statics, effort_ratios, holding_torques, worst_effort_ratio

    ratio, joint = worst_effort_ratio(scene, postures[0], "left")
    spread = Statics(scene).com_spread(postures[0])
    loads = [holding_torques(scene, postures[:1], [c], scene.route.contact_force_n)[0] for c in (None, "left")]
    ratios = np.nanmax([effort_ratios(scene, np.abs(t) + spread) for t in loads], axis=0)
    assert ratio == pytest.approx(np.nanmax(ratios))
    assert joint == int(np.nanargmax(ratios))


def test_com_spread_is_the_weight_moved_on_a_model_whose_base_carries_the_shift(scene, postures):
    """The base link's CoM moved by (M / m_base) d moves the weight's moment by M g x d: the torques change by A d."""
    import dataclasses

    from posegen.robot.statics import Statics

    margins = dataclasses.replace(scene.margins, com_uncertainty_m=0.01)
    statics = Statics(scene)
    statics.scene = _with_margins(scene, margins)
    shifted = Statics(scene)
    shifted.model = scene.model.copy()
    shifted.data = shifted.model.createData()
    base = shifted.model.inertias[1]
    mass, base_lever, inertia = base.mass, base.lever.copy(), base.inertia.copy()  # ``base`` is a view
    total = pin.computeTotalMass(scene.model)
    for posture in postures:
        rotation = _base_rotation(scene, posture)
        spread = statics.com_spread(posture)
        bound = np.zeros_like(spread)
        for d in ([0.01, 0.01, 0.0], [0.01, -0.01, 0.0], [-0.01, 0.01, 0.0], [-0.01, -0.01, 0.0]):
            lever = base_lever + total / mass * rotation.T @ np.array(d)
            shifted.model.inertias[1] = pin.Inertia(mass, lever, inertia)
            change = shifted.torques(posture, None, 0.0) - statics.torques(posture, None, 0.0)
            bound = np.maximum(bound, np.abs(change))
        assert spread == pytest.approx(bound, abs=1e-6)  # the worst corner of the square, joint by joint
        legs = [scene.joint_index(n) for n in ("leg_left_3_joint", "leg_right_3_joint")]
        assert np.all(spread[legs] > 1.0)  # N m: the stance legs carry it
        assert spread[scene.joint_index("arm_left_2_joint")] == pytest.approx(0.0, abs=1e-9)  # the arms do not


def test_com_spread_is_zero_without_an_uncertainty(scene, postures):
    import dataclasses

    from posegen.robot.statics import Statics

    statics = Statics(scene)
    statics.scene = _with_margins(scene, dataclasses.replace(scene.margins, com_uncertainty_m=0.0))
    assert not np.any(statics.com_spread(postures[0]))


def _with_margins(scene, margins):
    """A shallow stand-in of ``scene`` with other margins (the statics read only its margins and configuration)."""
    import copy

    other = copy.copy(scene)
    other.margins = margins
    return other


def _base_rotation(scene, posture):
    data = scene.model.createData()
    pin.forwardKinematics(scene.model, data, scene.configuration(posture))
    return data.oMi[1].rotation


def test_torque_pair_is_the_torques_and_spread_computed_alone_bit_for_bit(scene, postures):
    """The projection's one-pass pair: the same numbers as each torque and the spread on a fresh workspace."""
    import dataclasses

    from posegen.robot.statics import Statics

    margins = dataclasses.replace(scene.margins, com_uncertainty_m=0.01)
    paired, alone = Statics(scene), Statics(scene)
    paired.scene = alone.scene = _with_margins(scene, margins)
    for chain in ("left", "right"):
        for posture in postures:
            pair = paired.torque_pair(posture, chain, 30.0)
            assert np.array_equal(pair.unloaded, Statics(scene).torques(posture, None, 0.0))
            assert np.array_equal(pair.pressing, Statics(scene).torques(posture, chain, 30.0))
            assert np.array_equal(pair.spread, alone.com_spread(posture))
            assert np.any(pair.pressing != pair.unloaded) and np.any(pair.spread > 0.0)
            assert np.array_equal(pair.unloaded, _least_size_torques(scene, posture))  # the arithmetic of before


def _least_size_torques(scene, posture):
    """The unloaded holding torques (nj,) as the statics computed them before the one-pass pair, written out."""
    from posegen.robot import MOMENT_ARM_M

    model, data = scene.model, scene.model.createData()
    q = scene.configuration(posture)
    gravity = pin.computeGeneralizedGravity(model, data, q).copy()
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    frames = [scene.frame_id(f) for f in scene.stance.sole_frames]
    contact = np.vstack([pin.getFrameJacobian(model, data, f, pin.LOCAL) for f in frames])  # (6 k, nv)
    weight = np.tile([1.0, 1.0, 1.0, MOMENT_ARM_M, MOMENT_ARM_M, MOMENT_ARM_M], len(frames))
    split = contact[:, :6].T * weight[None, :]
    soles = split.T @ np.linalg.solve(split @ split.T, gravity[:6]) * weight
    return (gravity - contact.T @ soles)[scene.velocity_indices()]


def test_the_spatial_cross_product_matrices_are_the_cross_products():
    """``_ads(m) @ x`` is the motion cross product ``m x x`` = (w x v' + v x w', w x w'), linear parts first."""
    from posegen.robot.statics import _ads

    rng = np.random.default_rng(4)
    motions, others = rng.normal(size=(7, 6)), rng.normal(size=(7, 6))
    for motion, other, matrix in zip(motions, others, _ads(motions), strict=True):
        v, w, v2, w2 = motion[:3], motion[3:], other[:3], other[3:]
        expected = np.concatenate([np.cross(w, v2) + np.cross(v, w2), np.cross(w, w2)])
        np.testing.assert_allclose(matrix @ other, expected, rtol=1e-12, atol=1e-12)
    assert _ads(np.zeros((0, 6))).shape == (0, 6, 6)
