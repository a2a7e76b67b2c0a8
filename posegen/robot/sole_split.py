"""How two flat soles share the floor's wrench: the planner's split where the feet can carry it.

With both soles on the floor, statics leave the split between the feet open. The route's
torques were checked with the split of least size (:mod:`posegen.robot.statics`); the
stabilizer asks the feet for the same vertical shares where flat feet can carry them, the
closest ones otherwise:

* the total's ZMP ``p`` is carried with the second sole's share ``a`` of every force
  component, both centres of pressure offset alike from the foot rectangles' centres
  ``c1``, ``c2`` by ``e(a) = p - (c1 + a (c2 - c1))`` (the moment the shares cannot carry,
  borne by the soles' torques), yaw shared as the load;
* ``a`` is the least-size split's, clamped to the shares whose centres of pressure stay
  ``COP_MARGIN_M`` inside both rectangles; where none does (the ZMP beyond both feet's
  reach), the lever rule: ``p`` projected on the segment between the centres.
"""

from __future__ import annotations

import numpy as np

from posegen.robot.balance import centre_of_pressure
from posegen.robot.geometry import FloatArray
from posegen.robot.statics import MOMENT_ARM_M

COP_MARGIN_M = 0.01  # each sole's centre of pressure kept this far inside its rectangle
WEIGHT = np.array([1.0, 1.0, 1.0, MOMENT_ARM_M, MOMENT_ARM_M, MOMENT_ARM_M])  # the planner's least-size scaling


def _action(pose: FloatArray) -> FloatArray:
    """(6, 6) a wrench in the frame ``pose`` (4, 4) -> the same wrench in the world, about the origin."""
    rotation, origin = pose[:3, :3], pose[:3, 3]
    action = np.zeros((6, 6))
    action[:3, :3] = action[3:, 3:] = rotation
    action[3:, :3] = (
        np.array([[0.0, -origin[2], origin[1]], [origin[2], 0.0, -origin[0]], [-origin[1], origin[0], 0.0]]) @ rotation
    )
    return action


def least_size_map(poses: list[FloatArray]) -> FloatArray:
    """(2, 6) the soles' normal forces in the planner's least-size split, per unit of the total wrench.

    The split solves ``A w = total`` at least scaled size (:mod:`posegen.robot.statics`);
    its soles' normal forces are linear in the total. (The map depends on the soles'
    poses alone: it can be kept while they barely move.)
    """
    matrix = np.hstack([_action(pose) * WEIGHT[None, :] for pose in poses])  # (6, 12), acting on scaled wrenches
    solution = matrix.T @ np.linalg.inv(matrix @ matrix.T)  # (12, 6)
    return np.asarray(solution[[2, 8]])  # the normal forces (the scaling leaves forces as they are)


def least_size_share(total: FloatArray, poses: list[FloatArray], normal_map: FloatArray | None = None) -> float:
    """The second sole's share of the vertical load in the planner's least-size split of ``total`` (6,)."""
    first, second = (least_size_map(poses) if normal_map is None else normal_map) @ total
    return float(min(max(second / (first + second), 0.0), 1.0)) if first + second > 1e-9 else 0.5


def _feasible(
    zmp: FloatArray, centres: list[FloatArray], poses: list[FloatArray], half: FloatArray
) -> tuple[float, float]:
    """The shares ``a`` (low, high) whose offset ``e(a)`` keeps both centres of pressure inside (low > high: none).

    Python floats: on 2-vectors numpy's calls cost more than the arithmetic (the same numbers).
    """
    (start_x, start_y), (end_x, end_y) = centres[0][:2].tolist(), centres[1][:2].tolist()
    span_x, span_y = end_x - start_x, end_y - start_y
    base_x, base_y = float(zmp[0]) - start_x, float(zmp[1]) - start_y  # e(a) = base - a span
    limits = (half - COP_MARGIN_M).tolist()
    low, high = 0.0, 1.0
    for pose in poses:
        (xx, yx), (xy, yy) = pose[:2, :2].tolist()  # the sole's x (xx, xy) and y (yx, yy) in the world
        for axis_x, axis_y, limit in ((xx, xy, limits[0]), (yx, yy, limits[1])):
            at_zero = axis_x * base_x + axis_y * base_y  # e(a) . axis = at_zero + a slope
            slope = -(axis_x * span_x + axis_y * span_y)
            if abs(slope) < 1e-12:
                if abs(at_zero) > limit:
                    return 1.0, 0.0
                continue
            first, second = (-limit - at_zero) / slope, (limit - at_zero) / slope
            low, high = max(low, min(first, second)), min(high, max(first, second))
    return low, high


def split_wrench(
    total: FloatArray,
    poses: list[FloatArray],
    centre: FloatArray,
    half: FloatArray,
    normal_map: FloatArray | None = None,
) -> list[FloatArray]:
    """A world wrench (6,) at the world origin shared by two flat soles: each (6,) in its frame (LOCAL).

    Args:
        total: The wrench the floor applies, (6,) force N and moment N m about the world origin.
        poses: Each sole frame's world pose (4, 4).
        centre: (3,) the foot rectangle's centre in a sole frame.
        half: (2,) its half sizes, m.
        normal_map: :func:`least_size_map` of the poses, if kept; None: computed.

    Example:
        >>> left, right = split_wrench(total, robot.sole_poses, np.zeros(3), np.array([0.1, 0.065]))

    """
    force, moment = total[:3], total[3:]
    centres: list[FloatArray] = [pose[:3, :3] @ centre + pose[:3, 3] for pose in poses]
    if force[2] <= 1e-9:
        return _shared(total, 0.5, centres, np.zeros(2), poses)
    zmp = centre_of_pressure(force[2], moment[:2])
    span = centres[1][:2] - centres[0][:2]
    low, high = _feasible(zmp, centres, poses, half)
    if low <= high:
        share = min(max(least_size_share(total, poses, normal_map), low), high)
    else:  # the lever rule
        share = min(max(float((zmp - centres[0][:2]) @ span / (span @ span)), 0.0), 1.0)
    return _shared(total, share, centres, zmp - (centres[0][:2] + share * span), poses)


def _shared(
    total: FloatArray, share: float, centres: list[FloatArray], offset: FloatArray, poses: list[FloatArray]
) -> list[FloatArray]:
    """Both soles' wrenches (6,) LOCAL: shares (1 - share, share) of every force, pressure at centre + offset.

    Python floats: on 3-vectors numpy's calls cost more than the arithmetic (the same numbers).
    """
    force_x, force_y, force_z, _, _, moment_z = total.tolist()
    offset_x, offset_y = offset.tolist()
    shares = (1.0 - share, share)
    points = [(float(c[0]) + offset_x, float(c[1]) + offset_y) for c in centres]  # the centres of pressure, z = 0
    yaw = moment_z - sum(s * (x * force_y - y * force_x) for s, (x, y) in zip(shares, points, strict=True))
    out = []
    for part_share, (x, y), pose in zip(shares, points, poses, strict=True):
        (r00, r01, r02, origin_x), (r10, r11, r12, origin_y), (r20, r21, r22, origin_z) = pose[:3].tolist()
        fx, fy, fz = part_share * force_x, part_share * force_y, part_share * force_z  # its force
        lx, ly, lz = x - origin_x, y - origin_y, 0.0 - origin_z  # the lever from the sole's origin
        tx, ty, tz = ly * fz - lz * fy, lz * fx - lx * fz, lx * fy - ly * fx + part_share * yaw  # its torque
        out.append(
            np.array(
                [
                    r00 * fx + r10 * fy + r20 * fz,  # the rotation's transpose: world -> sole
                    r01 * fx + r11 * fy + r21 * fz,
                    r02 * fx + r12 * fy + r22 * fz,
                    r00 * tx + r10 * ty + r20 * tz,
                    r01 * tx + r11 * ty + r21 * tz,
                    r02 * tx + r12 * ty + r22 * tz,
                ]
            )
        )
    return out
