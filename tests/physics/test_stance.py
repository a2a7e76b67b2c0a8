"""The stance: the plan's floor points follow the soles from where the plan puts them to where the robot stands."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from posegen.physics.stance import PlannedFeet


def _sole(x: float, y: float, yaw: float) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3] = pin.rpy.rpyToMatrix(0.0, 0.0, yaw)
    pose[:2, 3] = [x, y]
    return pose


CENTRE = np.array([-0.0055, 0.0, 0.0])  # TALOS's foot rectangle centre in its sole's frame, m
ANCHOR = _sole(-0.009, 0.085, 0.0)
PLANNED = _sole(-0.009, -0.085, 0.0)
STANDING = _sole(-0.036, -0.036, 0.04)  # the second sole 5 cm inward of its plan, turned 2.3 deg


def follow_feet(point: np.ndarray, soles: tuple[tuple[np.ndarray, np.ndarray], ...], centre: np.ndarray) -> np.ndarray:
    """The point moved by the soles, each (planned, standing)."""
    (first, first_standing), (second, second_standing) = soles
    return PlannedFeet((first, second), centre).follow(point, (first_standing, second_standing))


def _centre(pose: np.ndarray) -> np.ndarray:
    return pose[:2, :3] @ CENTRE + pose[:2, 3]


def test_points_stay_where_the_robot_stands_as_planned() -> None:
    soles = ((ANCHOR, ANCHOR), (PLANNED, PLANNED))
    for point in np.random.default_rng(0).uniform(-0.3, 0.3, (20, 2)):
        assert np.allclose(follow_feet(point, soles, CENTRE), point, atol=1e-15)


def test_a_point_under_a_foot_moves_with_that_foot() -> None:
    """Under the second sole (at its centre, or 2 cm beyond it outward): where that sole's frame puts it standing;
    under the anchor: where it was."""
    soles = ((ANCHOR, ANCHOR), (PLANNED, STANDING))
    assert np.allclose(follow_feet(_centre(PLANNED), soles, CENTRE), _centre(STANDING), atol=1e-12)
    outward = _centre(PLANNED) + np.array([0.005, -0.02])  # the plan's ZMP 2 cm outward, 5 mm ahead
    local = np.linalg.solve(PLANNED, np.array([*outward, 0.0, 1.0]))
    assert np.allclose(follow_feet(outward, soles, CENTRE), (STANDING @ local)[:2], atol=1e-12)
    assert np.allclose(follow_feet(_centre(ANCHOR), soles, CENTRE), _centre(ANCHOR), atol=1e-15)


def test_a_point_between_the_feet_moves_by_its_share() -> None:
    soles = ((ANCHOR, ANCHOR), (PLANNED, STANDING))
    for along in (0.25, 0.5, 0.75):
        point = _centre(ANCHOR) + along * (_centre(PLANNED) - _centre(ANCHOR))
        local = np.linalg.solve(PLANNED, np.array([*point, 0.0, 1.0]))
        expected = (1 - along) * point + along * (STANDING @ local)[:2]
        assert np.allclose(follow_feet(point, soles, CENTRE), expected, atol=1e-12)
    midway = follow_feet(0.5 * (_centre(ANCHOR) + _centre(PLANNED)), soles, CENTRE)
    assert 0.02 < np.linalg.norm(midway - 0.5 * (_centre(ANCHOR) + _centre(PLANNED))) < 0.03  # half of 5 cm
