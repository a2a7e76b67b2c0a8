"""Where ``posegen robot init`` puts the table: before and below the shoulders (by the reach), clear of the robot."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from posegen.robot import FloatArray, FrameConfig

TABLE_DEPTH = 0.7  # table top this many arm lengths below the shoulders, its centre as far in front
TABLE_CLEARANCE_M = 0.03  # the drafted table's near edge from the robot at the reference

# top centre (m), size (m), spots along x and y in the table's frame (m), yaw (deg: its x axis the robot's forward)
Table = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, ...], tuple[float, ...], float]


def place_table(heading: pin.SE3, shoulder: FloatArray, reach: float, floor: float, body: FloatArray) -> Table:
    """A table TABLE_DEPTH arm lengths in front of and below the shoulders, heights from the floor.

    The table's frame is the heading's: its x axis the robot's forward, its y axis the
    robot's left (so the spots on the table's +y side are the left hand's).

    Moved forward, if need be, to stand TABLE_CLEARANCE_M clear of the robot's geometry at
    the reference (``body``: (k, 3) vertices in the heading frame, heights from the floor).
    """
    local = heading.actInv(shoulder)
    height = local[2] - TABLE_DEPTH * reach - floor
    length, width = round(0.5 * reach, 2), round(2 * (abs(float(local[1])) + 0.5 * reach), 2)
    x = local[0] + TABLE_DEPTH * reach
    beside = body[(body[:, 2] > height - 0.04 - TABLE_CLEARANCE_M) & (np.abs(body[:, 1]) < width / 2)]
    if len(beside):
        x = max(x, float(beside[:, 0].max()) + TABLE_CLEARANCE_M + length / 2)
    centre = heading.act(np.array([x, 0.0, 0.0]))
    spots_x = tuple(round(v, 3) for v in (-0.3 * length, 0.0, 0.3 * length))
    half = 0.4 * width
    spots_y = tuple(round(float(v), 3) for v in np.linspace(-half, half, 6))
    top = (round(float(centre[0]), 3) + 0.0, round(float(centre[1]), 3) + 0.0, round(float(height), 3) + 0.0)
    yaw = round(float(np.degrees(np.arctan2(heading.rotation[1, 0], heading.rotation[0, 0]))), 3) + 0.0
    yaw = 180.0 if yaw <= -180.0 else yaw  # in (-180, 180]
    return top, (length, width, 0.04), spots_x, spots_y, yaw


def arm_length(
    model: pin.Model, data: pin.Data, joints: tuple[str, ...], hand: str, contact: tuple[FrameConfig, ...]
) -> float:
    """Shoulder to the hand's contact: the sum of the distances between the arm's joints, then to the contact (m)."""
    ids = [model.getJointId(j) for j in joints]
    length = sum(float(np.linalg.norm(model.jointPlacements[j].translation)) for j in ids[1:])
    touch = np.mean([data.oMf[model.getFrameId(f.parent)].act(np.array(f.xyz_m)) for f in contact], axis=0)
    return length + float(np.linalg.norm(touch - data.oMi[ids[-1]].translation))
