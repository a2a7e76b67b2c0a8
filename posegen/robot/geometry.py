"""Small geometric helpers: planar poses, support polygons, roll/pitch of a frame, a frame's id."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from posegen.errors import ConfigError, unknown_name
from posegen.numeric import FloatArray as FloatArray  # re-exported for the robot package

Indices = Sequence[int] | NDArray[np.integer[Any]]  # row or column indices


def yaw_rotation(yaw_rad: float) -> FloatArray:
    """Rotation matrix about z by ``yaw_rad``. Shape (3, 3)."""
    c, s = np.cos(yaw_rad), np.sin(yaw_rad)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def flatten_on_floor(pose: FloatArray) -> FloatArray:
    """Keep x, y and yaw of a homogeneous pose, put it at z = 0 with z up.

    Args:
        pose: Homogeneous transform, shape (4, 4).

    Returns:
        A new homogeneous transform, shape (4, 4).

    """
    flat = np.eye(4)
    flat[:3, :3] = yaw_rotation(float(np.arctan2(pose[1, 0], pose[0, 0])))
    flat[:2, 3] = pose[:2, 3]
    return flat


def tilt_angles(rotation: FloatArray) -> tuple[float, float]:
    """Roll and pitch (rad) of a frame with respect to a horizontal plane.

    Uses the z-y-x (yaw-pitch-roll) convention of the frame's rotation expressed in the
    plane frame: roll about x, pitch about y; both zero iff the frame's z axis is the
    plane normal.

    Args:
        rotation: Rotation of the frame in the plane frame, shape (3, 3).

    Returns:
        (roll, pitch) in rad.

    """
    pitch = float(np.arcsin(np.clip(-rotation[2, 0], -1.0, 1.0)))
    roll = float(np.arctan2(rotation[2, 1], rotation[2, 2]))
    return roll, pitch


def convex_hull_clockwise(points: FloatArray) -> FloatArray:
    """Convex hull of planar points, vertices in clockwise order.

    Args:
        points: Planar points, shape (n, 2).

    Returns:
        Hull vertices, shape (h, 2), clockwise (the order placo's CoM polygon expects).

    """
    pts = sorted({(float(x), float(y)) for x, y in points})
    if len(pts) < 3:
        raise ValueError("a support polygon needs at least 3 distinct points")

    def cross(o: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list[tuple[float, float]] = []
    upper: list[tuple[float, float]] = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    counter_clockwise = lower[:-1] + upper[:-1]
    return np.array(counter_clockwise[::-1])


def polygon_margin(polygon_cw: FloatArray, point: FloatArray) -> float:
    """Signed distance (m) from a point to the boundary of a convex polygon.

    Args:
        polygon_cw: Clockwise convex polygon, shape (h, 2).
        point: Planar point, shape (2,).

    Returns:
        Positive inside (distance to the nearest edge line), negative outside.

    On Python floats (17 -> 2 us for a sole's rectangle: the pool asks at every posture),
    with numpy's numbers: ``sqrt(x x + y y)`` is what ``np.linalg.norm`` gives for a
    2-vector and ``x0 y0 + x1 y1`` what its dot gives (checked on 100 000 random cases).

    Example:
        >>> polygon_margin(np.array([[0.1, 0.1], [0.1, -0.1], [-0.1, -0.1], [-0.1, 0.1]]), np.zeros(2))
        0.1

    """
    margin = np.inf
    px, py = float(point[0]), float(point[1])
    corners = np.asarray(polygon_cw, dtype=float).tolist()
    n = len(corners)
    for i in range(n):
        (ax, ay), (bx, by) = corners[i], corners[(i + 1) % n]
        ex, ey = bx - ax, by - ay
        length = math.sqrt(ex * ex + ey * ey)
        # Clockwise: the interior is on the right of each edge, along (ey, -ex).
        margin = min(margin, ey / length * (px - ax) + -ex / length * (py - ay))
    return float(margin)


def cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """The cross product of two 3-vectors (numpy's is slow on one pair; the same numbers).

    Example:
        >>> cross(np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
        array([0., 0., 1.])

    """
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def frame_id(model: pin.Model, name: str) -> int:
    """Pinocchio id of a frame.

    Raises:
        ConfigError: No such frame (the valid ones are listed).

    """
    if not model.existFrame(name):
        raise ConfigError(unknown_name("frame", name, (f.name for f in model.frames)))
    return int(model.getFrameId(name))
