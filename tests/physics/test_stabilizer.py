"""The stabilizer: a free-standing perturbed robot stands still; its pieces (the support hull, the
references a hand's push asks for) do what they say."""

from __future__ import annotations

import numpy as np
import pytest

from posegen.physics.builder import Built
from posegen.physics.gains import Gains
from posegen.physics.nominal import NominalRobot
from posegen.physics.plan import Plan
from posegen.physics.run import Run
from posegen.physics.sensors import SensorNoise, Sensors
from posegen.physics.stabilizer import Hull, Reference, clamp_into, references
from posegen.physics.tool import Tool
from posegen.robot import Scene, convex_hull_clockwise, polygon_margin


def standing_plan(scene: Scene, seconds: float, period_s: float = 0.002) -> Plan:
    """The reference posture held for ``seconds``, as a plan (no route)."""
    import pinocchio as pin

    count = round(seconds / period_s)
    q = scene.configuration(scene.reference)
    data = scene.model.createData()
    com = pin.centerOfMass(scene.model, data, q)[:2]
    pin.framesForwardKinematics(scene.model, data, q)
    hands = {c.name: data.oMf[scene.frame_id(c.frame(c.contact_kind))].homogeneous for c in scene.chains}
    return Plan(
        np.arange(count) * period_s,
        0.0,
        np.repeat(scene.reference[None], count, axis=0),
        np.zeros((count, len(scene.joint_names))),
        np.repeat(com[None], count, axis=0),
        np.zeros((count, 2)),
        np.repeat(com[None], count, axis=0),  # at rest, the ZMP is under the CoM
        np.full(count, q[2]),
        np.repeat(pin.Quaternion(q[3:7]).toRotationMatrix()[None], count, axis=0),
        {c: np.repeat(h[None], count, axis=0) for c, h in hands.items()},
    )


def test_a_perturbed_robot_stands_ten_seconds(
    scene: Scene, perturbed: Built, gains: Gains, tools: dict[str, Tool]
) -> None:
    """Free-standing, its stance closed on the floor at start: the pelvis keeps its height, the soles
    do not slip and stay flat, nothing but the soles touches anything."""
    plan = standing_plan(scene, 10.0)
    run = Run(scene, perturbed, gains, plan, (), Sensors(perturbed.layout, SensorNoise(), 1), tools, 30.0, 1)
    result = run.run()
    truth = result.truth
    assert result.fell_at_s is None
    height = truth.pelvis_z - truth.pelvis_z[250]  # after the first half second's settling
    assert np.abs(height[250:]).max() < 3e-3
    slip = np.linalg.norm(truth.soles_xy - truth.soles_xy[0], axis=2)
    assert slip.max() < 1e-3
    sites = [s.site for s in perturbed.layout.soles.values()]
    assert max(np.abs(run.data.site_xmat[s].reshape(3, 3)[2, :2]).max() for s in sites) < 0.01  # flat (10 mrad)
    assert np.nanmin(truth.zmp_margin[250:]) > 0.03
    assert not truth.touches


def test_the_hull_margin_is_posegen_s() -> None:
    rng = np.random.default_rng(0)
    points = rng.normal(size=(9, 2))
    hull = Hull.of(points)
    for point in rng.normal(size=(20, 2)):
        assert hull.margin(point) == pytest.approx(polygon_margin(convex_hull_clockwise(points), point), abs=1e-12)
    outside = np.array([5.0, 5.0])
    assert hull.margin(clamp_into(hull, outside, 0.1)) == pytest.approx(0.1, abs=1e-3)


def test_a_push_moves_the_com_only_when_the_zmp_would_leave_the_margin(scene: Scene, tools: dict[str, Tool]) -> None:
    robot = NominalRobot(scene, tools)
    robot.update(scene.reference)
    polygon = Hull.of(
        np.vstack(
            [
                (pose @ np.array([[x, y, 0, 1] for x in scene.stance.foot_x_m for y in scene.stance.foot_y_m]).T)[:2].T
                for pose in robot.sole_poses
            ]
        )
    )
    com = robot.com()[:2]
    at_rest = Reference(com, np.zeros(2), com, 1.0)
    hand = robot.pose(robot.contact_frames["left"])[:2, 3]
    weight = robot.mass_kg * 9.81
    zmp, reference = references(robot, {"left": np.array([0.0, 0.0, 30.0, 0, 0, 0])}, at_rest, polygon, 0.02)
    assert np.allclose(reference, com) and np.allclose(zmp, (weight * com - 30.0 * hand) / (weight - 30.0))
    assert (zmp - com) @ (hand - com) < 0  # the table lifts the hand: the floor's pressure moves away from it
    zmp, reference = references(robot, {"left": np.array([0.0, 0.0, 300.0, 0, 0, 0])}, at_rest, polygon, 0.02)
    assert polygon.margin(zmp) == pytest.approx(0.02, abs=1e-3)
    assert np.allclose((weight * reference - 300.0 * hand) / (weight - 300.0), zmp)  # the CoM moved to hold it
    assert (reference - com) @ (hand - com) > 0


def test_the_soles_give_way_to_the_force_between_them_and_not_to_the_net_one(scene: Scene) -> None:
    """Internal horizontal forces (the true legs do not close where the nominal ones do) move the soles apart
    along them, equally and oppositely; the net horizontal force, carried as the shares say, moves neither."""
    from posegen.physics.stabilizer import BAND, K_FOOT_SHEAR, _sole_twist

    pose = np.eye(4)
    share = np.array([5.0, -3.0, 440.0, 0.0, 0.0, 0.0])  # each sole's share of the net wrench (local)
    squeeze = np.array([0.0, 70.0, 0.0, 0.0, 0.0, 0.0])  # the floor pushes the feet apart along y
    none = np.zeros(3)
    left = _sole_twist(pose, share + squeeze, share, none, none, 880.0)
    right = _sole_twist(pose, share - squeeze, share, none, none, 880.0)
    assert left[1] == pytest.approx(K_FOOT_SHEAR * (70.0 - BAND[1])) and left[1] > 0
    assert left + right == pytest.approx(np.zeros(6))
    assert _sole_twist(pose, share, share, none, none, 880.0) == pytest.approx(np.zeros(6))


def test_the_desired_zmp_asks_no_leg_past_its_limit(scene: Scene, tools: dict[str, Tool]) -> None:
    """A ZMP over one foot loads its hip past a (reduced) limit: the stabilizer moves it back toward the
    reference just as far as every joint allows, re-checked on the nominal model's torques."""
    from posegen.physics.stabilizer import Stabilizer

    robot = NominalRobot(scene, tools)
    robot.update(scene.reference)
    stabilizer = Stabilizer(scene, robot)
    weight = robot.mass_kg * 9.81
    centres = [pose[:2, 3] for pose in robot.sole_poses]
    reference = 0.5 * (centres[0] + centres[1])
    desired = centres[1] + 0.5 * (centres[1] - reference)  # beyond the second sole's centre

    def total_at(zmp: np.ndarray) -> np.ndarray:
        return np.array([0.0, 0.0, weight, zmp[1] * weight, -zmp[0] * weight, 0.0])

    def torques_at(zmp: np.ndarray) -> np.ndarray:
        return np.abs(robot.sole_torques(robot.sole_split(total_at(zmp))))

    at_reference, at_desired = torques_at(reference), torques_at(desired)
    limit = np.full(len(scene.joint_names), np.inf)
    worst = int(np.argmax(at_desired - at_reference))
    limit[worst] = 0.5 * (at_reference[worst] + at_desired[worst])  # between what each ZMP asks of that joint
    stabilizer._limit = limit
    zmp, shares = stabilizer._within_torques(total_at(reference), reference, desired)
    step = np.linalg.norm(zmp - reference) / np.linalg.norm(desired - reference)
    assert 0.0 < step < 1.0
    assert np.all(torques_at(zmp) <= limit + 1e-9)
    assert np.abs(robot.sole_torques(shares))[worst] == pytest.approx(torques_at(zmp)[worst])
    further = reference + min(step + 0.05, 1.0) * (desired - reference)
    assert torques_at(further)[worst] > limit[worst]  # the largest step within the limit (bisection, 1/64)
    stabilizer._limit = np.full(len(scene.joint_names), np.inf)
    assert np.allclose(stabilizer._within_torques(total_at(reference), reference, desired)[0], desired)


def test_a_sole_on_its_edge_is_told_by_its_centre_of_pressure(scene: Scene) -> None:
    from posegen.physics.stabilizer import EDGE_M, LIGHT_SHARE, is_light, on_edge

    (x0, x1), (y0, y1) = scene.stance.foot_x_m, scene.stance.foot_y_m
    rectangle = Hull.of(np.array([[x0, y0], [x0, y1], [x1, y1], [x1, y0]]))

    def at(x: float, y: float, force: float = 700.0) -> np.ndarray:  # the floor's wrench, its centre of pressure
        return np.array([0.0, 0.0, force, y * force, -x * force, 0.0])

    centre = (0.5 * (x0 + x1), 0.5 * (y0 + y1))
    assert not on_edge(at(*centre), rectangle, 900.0)
    assert on_edge(at(centre[0], y0 + 0.5 * EDGE_M), rectangle, 900.0)  # its outer side
    assert on_edge(at(x1 - 0.5 * EDGE_M, centre[1]), rectangle, 900.0)  # its toe
    assert not on_edge(at(centre[0], y0 + 2.0 * EDGE_M), rectangle, 900.0)
    light = 0.5 * LIGHT_SHARE * 900.0
    assert not on_edge(at(centre[0], y0, light), rectangle, 900.0)  # a light sole may stand on its edge
    assert is_light(at(*centre, light), 900.0) and not is_light(at(*centre, LIGHT_SHARE * 900.0), 900.0)


def test_a_sole_on_its_edge_rests_the_com_shift_and_the_levelling(scene: Scene, tools: dict[str, Tool]) -> None:
    """The CoM 5 cm off its reference and the base tilted: with both soles flat, both move alike along the
    floor and turn alike; with a loaded sole on its edge, neither (its admittance alone acts)."""
    import pinocchio as pin

    from posegen.physics.stabilizer import MAX_COM_SPEED, SoleReadings, Stabilizer

    robot = NominalRobot(scene, tools)
    robot.update(scene.reference)
    weight = robot.mass_kg * 9.81
    com = robot.com()[:2]
    planned = Reference(com + np.array([0.05, 0.0]), np.zeros(2), com + np.array([0.05, 0.0]), float(robot.q[2]))
    tilted = (pin.rpy.rpyToMatrix(0.05, 0.0, 0.0), np.eye(3))
    flat = SoleReadings(tuple(np.array([0.0, 0.0, 0.5 * weight, 0.0, 0.0, 0.0]) for _ in robot.soles))
    twists = Stabilizer(scene, robot).step(flat, {}, tilted, planned, 0.004)
    assert np.allclose(twists[0][:2], twists[1][:2]) and twists[0][0] == pytest.approx(-MAX_COM_SPEED)
    assert twists[0][3] != 0.0 and twists[0][3] == pytest.approx(twists[1][3])  # both turn with the base's tilt
    y0 = scene.stance.foot_y_m[0]
    edge = np.array([0.0, 0.0, 0.5 * weight, y0 * 0.5 * weight, 0.0, 0.0])  # the second sole on its outer side
    twists = Stabilizer(scene, robot).step(SoleReadings((flat.wrenches[0], edge)), {}, tilted, planned, 0.004)
    assert np.allclose([t[:2] for t in twists], 0.0, atol=1e-12)  # no shift (no horizontal force to give way to)
    assert twists[0][3] == pytest.approx(0.0, abs=1e-12)  # the flat sole does not turn with the base either


def test_the_plan_s_balance_follows_the_second_sole_to_where_it_stands(scene: Scene, tools: dict[str, Tool]) -> None:
    """The robot believes its second sole 3 cm from the plan's: a planned CoM under that sole's centre becomes one
    under its believed centre, and the desired ZMP (the DCM on its reference) lies there too; under the anchor sole
    nothing moves."""
    from posegen.physics.stabilizer import SoleReadings, Stabilizer

    robot = NominalRobot(scene, tools)
    robot.update(scene.reference)
    stabilizer = Stabilizer(scene, robot)
    (x0, x1), (y0, y1) = scene.stance.foot_x_m, scene.stance.foot_y_m
    centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2, 0.0])
    anchor, second = (scene.sole_poses[f] for f in scene.stance.sole_frames)
    planned_centre = second[:2, :3] @ centre + second[:2, 3]
    moved = robot.sole_poses[1].copy()
    moved[:2, 3] += [-0.02, 0.025]  # where the encoders say the second sole stands
    robot.sole_poses[1] = moved
    believed_centre = moved[:2, :3] @ centre + moved[:2, 3]
    reference = Reference(planned_centre, np.zeros(2), planned_centre, float(robot.q[2]))
    stood = stabilizer._as_stood(reference)
    assert np.allclose(stood.com, believed_centre, atol=2e-4) and np.allclose(stood.zmp, stood.com)
    under_anchor = anchor[:2, :3] @ centre + anchor[:2, 3]
    kept = stabilizer._as_stood(Reference(under_anchor, np.zeros(2), under_anchor, float(robot.q[2])))
    assert np.allclose(kept.com, under_anchor, atol=2e-4)
    stabilizer.com_bias = reference.com - robot.com()[:2]  # the robot's CoM where the plan puts it
    weight = robot.mass_kg * 9.81
    flat = SoleReadings(tuple(np.array([0.0, 0.0, 0.5 * weight, 0.0, 0.0, 0.0]) for _ in robot.soles))
    stabilizer.step(flat, {}, (np.eye(3), np.eye(3)), reference, 0.004)
    assert np.linalg.norm(stabilizer.zmp_desired - believed_centre) > 0.02  # the CoM 3 cm off the stood reference
    stabilizer.com_bias = believed_centre - robot.com()[:2]  # the robot's CoM over where that sole stands
    stabilizer._com = None
    stabilizer.step(flat, {}, (np.eye(3), np.eye(3)), reference, 0.004)
    assert np.allclose(stabilizer.zmp_desired, believed_centre, atol=1e-3)
