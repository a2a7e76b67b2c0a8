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
