import numpy as np
import pytest

from posegen.robot import convex_hull_clockwise, flatten_on_floor, polygon_margin, tilt_angles


def test_hull_is_clockwise_and_drops_interior_points():
    pts = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.5], [0.2, 0.7]])
    hull = convex_hull_clockwise(pts)
    assert len(hull) == 4
    x, y = hull[:, 0], hull[:, 1]
    signed_area = 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y)
    assert signed_area < 0  # clockwise


def test_polygon_margin_inside_outside():
    square = convex_hull_clockwise(np.array([[0, 0], [2, 0], [2, 2], [0, 2]]))
    assert polygon_margin(square, np.array([1.0, 1.0])) == pytest.approx(1.0)
    assert polygon_margin(square, np.array([0.5, 1.0])) == pytest.approx(0.5)
    assert polygon_margin(square, np.array([3.0, 1.0])) == pytest.approx(-1.0)


def test_tilt_angles_match_rotations():
    import pinocchio as pin

    rotation = pin.rpy.rpyToMatrix(0.1, -0.2, 0.7)
    roll, pitch = tilt_angles(rotation)
    assert roll == pytest.approx(0.1) and pitch == pytest.approx(-0.2)


def test_flatten_keeps_xy_yaw():
    import pinocchio as pin

    pose = np.eye(4)
    pose[:3, :3] = pin.rpy.rpyToMatrix(0.01, 0.02, 0.5)
    pose[:3, 3] = [0.3, -0.2, 0.01]
    flat = flatten_on_floor(pose)
    assert flat[2, 3] == 0 and flat[:2, 3] == pytest.approx([0.3, -0.2])
    assert np.arctan2(flat[1, 0], flat[0, 0]) == pytest.approx(0.5, abs=1e-3)
    assert flat[:3, 2] == pytest.approx([0, 0, 1])
