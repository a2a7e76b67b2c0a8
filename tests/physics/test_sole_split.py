"""The soles' split: the planner's least-size shares where flat feet carry them, the closest feasible ones else."""

from __future__ import annotations

import numpy as np
import pytest

from posegen.physics.nominal import NominalRobot
from posegen.physics.tool import Tool
from posegen.robot import Scene
from posegen.robot.sole_split import COP_MARGIN_M, least_size_share, split_wrench


def _split(scene: Scene, tools: dict[str, Tool], zmp: tuple[float, float]) -> tuple[NominalRobot, list[np.ndarray]]:
    robot = NominalRobot(scene, tools)
    robot.update(scene.reference)
    weight = 880.0
    total = np.array([3.0, -2.0, weight, zmp[1] * weight, -zmp[0] * weight, 1.5])
    return robot, robot.sole_split(total)


def _cops(scene: Scene, shares: list[np.ndarray]) -> list[np.ndarray]:
    return [np.array([-w[4], w[3]]) / w[2] for w in shares if w[2] > 1e-6]


@pytest.mark.parametrize("zmp", [(-0.01, 0.03), (0.02, -0.05), (0.0, 0.0)])
def test_a_zmp_between_the_feet_is_shared_as_the_planner_shares_it(
    scene: Scene, tools: dict[str, Tool], zmp: tuple[float, float]
) -> None:
    robot, shares = _split(scene, tools, zmp)
    total = robot.soles_total(tuple(shares))
    assert np.allclose(total, [3.0, -2.0, 880.0, zmp[1] * 880.0, -zmp[0] * 880.0, 1.5])
    planned = least_size_share(total, robot.sole_poses)
    assert shares[1][2] / 880.0 == pytest.approx(planned, abs=1e-9)
    (x0, x1), (y0, y1) = scene.stance.foot_x_m, scene.stance.foot_y_m
    for cop in _cops(scene, shares):
        assert x0 + COP_MARGIN_M - 1e-9 <= cop[0] <= x1 - COP_MARGIN_M + 1e-9
        assert y0 + COP_MARGIN_M - 1e-9 <= cop[1] <= y1 - COP_MARGIN_M + 1e-9


def test_a_zmp_over_one_foot_puts_the_other_as_light_as_the_rectangles_allow(
    scene: Scene, tools: dict[str, Tool]
) -> None:
    robot = NominalRobot(scene, tools)
    robot.update(scene.reference)
    outer = robot.sole_poses[0][1, 3] + 0.8 * scene.stance.foot_y_m[1]  # beyond the first sole's centre
    _, shares = _split(scene, tools, (robot.sole_poses[0][0, 3], outer))
    assert np.allclose(
        robot.soles_total(tuple(shares))[2:5], [880.0, outer * 880.0, -robot.sole_poses[0][0, 3] * 880.0]
    )
    planned = least_size_share(robot.soles_total(tuple(shares)), robot.sole_poses)
    assert shares[1][2] / 880.0 < planned  # the least-size split asks the far foot for more than it can carry
    (x0, x1), (y0, y1) = scene.stance.foot_x_m, scene.stance.foot_y_m
    for cop in _cops(scene, shares):
        assert y0 - 1e-9 <= cop[1] <= y1 + 1e-9 and x0 - 1e-9 <= cop[0] <= x1 + 1e-9


def test_the_split_keeps_the_given_wrench() -> None:
    poses = [np.eye(4), np.eye(4)]
    poses[0][1, 3], poses[1][1, 3] = 0.1, -0.1
    total = np.array([5.0, 1.0, 500.0, 500 * 0.02, -500 * 0.01, 0.3])
    shares = split_wrench(total, poses, np.zeros(3), np.array([0.1, 0.06]))
    back = sum(np.concatenate([w[:3], w[3:] + np.cross(p[:3, 3], w[:3])]) for w, p in zip(shares, poses, strict=True))
    assert np.allclose(back, total)


def _reference_split(total: np.ndarray, poses: list[np.ndarray], centre: np.ndarray, half: np.ndarray) -> list:
    """The split written with numpy on whole vectors, as the module's docstring states it."""
    centres = [p[:3, :3] @ centre + p[:3, 3] for p in poses]
    force, moment = total[:3], total[3:]
    zmp = np.array([-moment[1], moment[0]]) / force[2]
    span, base = centres[1][:2] - centres[0][:2], zmp - centres[0][:2]
    low, high = 0.0, 1.0
    for pose in poses:
        for axis, limit in zip(pose[:2, :2].T, half - COP_MARGIN_M, strict=True):
            ends = sorted(((-limit - axis @ base) / -(axis @ span), (limit - axis @ base) / -(axis @ span)))
            low, high = max(low, ends[0]), min(high, ends[1])
    if low <= high:
        share = min(max(least_size_share(total, poses), low), high)
    else:
        share = min(max(float(base @ span / (span @ span)), 0.0), 1.0)
    offset = zmp - (centres[0][:2] + share * span)
    points = [np.array([c[0] + offset[0], c[1] + offset[1], 0.0]) for c in centres]
    parts = (1.0 - share, share)
    yaw = moment[2] - sum(s * np.cross(p, force)[2] for s, p in zip(parts, points, strict=True))
    out = []
    for s, point, pose in zip(parts, points, poses, strict=True):
        torque = np.cross(point - pose[:3, 3], s * force) + np.array([0.0, 0.0, s * yaw])
        out.append(np.concatenate([pose[:3, :3].T @ (s * force), pose[:3, :3].T @ torque]))
    return out


def test_the_split_on_floats_gives_the_whole_vector_formulas_numbers() -> None:
    rng = np.random.default_rng(3)
    for _ in range(300):
        poses = []
        for _ in range(2):
            pose = np.eye(4)
            yaw, tilt = rng.normal(0.0, 0.3), rng.normal(0.0, 0.05, 2)
            rz = np.array([[np.cos(yaw), -np.sin(yaw), 0.0], [np.sin(yaw), np.cos(yaw), 0.0], [0.0, 0.0, 1.0]])
            rx = np.array(
                [[1.0, 0.0, 0.0], [0.0, np.cos(tilt[0]), -np.sin(tilt[0])], [0.0, np.sin(tilt[0]), np.cos(tilt[0])]]
            )
            ry = np.array(
                [[np.cos(tilt[1]), 0.0, np.sin(tilt[1])], [0.0, 1.0, 0.0], [-np.sin(tilt[1]), 0.0, np.cos(tilt[1])]]
            )
            pose[:3, :3], pose[:3, 3] = rz @ ry @ rx, rng.normal(0.0, 0.1, 3)
            poses.append(pose)
        centre, half = np.array([rng.normal(0.0, 0.02), rng.normal(0.0, 0.01), 0.0]), np.array([0.1, 0.065])
        total = rng.normal(0.0, 50.0, 6)
        total[2] = 400.0 + abs(total[2]) * 10.0
        expected = _reference_split(total, poses, centre, half)
        for got, want in zip(split_wrench(total, poses, centre, half), expected, strict=True):
            np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-9)
