"""Which way a drafted humanoid faces: its root's x axis, unless both knees bend the other way.

URDFs name no "forward". The draft takes the root's x axis (REP 103), which most humanoids
follow; some roots point backwards (iCub's root x axis points behind the robot). A knee
whose range is clearly one-sided bends the shank backwards, so the foot moves behind the
knee when it flexes: when both knees say the root's x axis is behind the robot, the draft
turns the robot's forward (and so its left and right, its table side) around, and says so.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.draft.stance import Subtree, foot_joint, joint_axis, joint_path, knee_of
from posegen.robot import FloatArray, yaw_rotation

ONE_SIDED = 2.0  # a knee's range is one-sided when one side is at least this many times the other
CLEAR = 0.5  # a vote counts when the foot's flexion motion is this aligned with forward (cosine)
TURNED = (
    "the robot faces its root's -x axis (both knees bend that way): forward, left and right, and the table's "
    "side are taken from there; check with `posegen view`"
)


@dataclass(frozen=True, eq=False)
class Bearing:
    """How the robot is turned: its root's pose, the up axis, and the horizontal directions."""

    root: pin.SE3  # the root's pose (its orientation puts the up axis up)
    up: str  # the root's axis pointing up, e.g. "+z"
    forward: FloatArray  # (3,) world, horizontal
    left: FloatArray  # (3,) world, up x forward
    heading: pin.SE3  # the yaw of forward, at the origin

    def turned(self) -> Bearing:
        """The same root, facing the other way (forward and left reversed)."""
        forward = -self.forward
        heading = pin.SE3(yaw_rotation(float(np.arctan2(forward[1], forward[0]))), np.zeros(3))
        return Bearing(self.root, self.up, forward, -self.left, heading)


def forward_of(root: pin.SE3) -> FloatArray:
    """The robot's forward direction in the world: its root's x axis, levelled. Shape (3,)."""
    for column in (0, 2, 1):
        v = root.rotation[:, column].copy()
        v[2] = 0.0
        if np.linalg.norm(v) > 0.5:
            return np.asarray(v / np.linalg.norm(v))
    return np.array([1.0, 0.0, 0.0])


def knees_face_back(
    model: pin.Model,
    data: pin.Data,
    children: dict[int, list[int]],
    subtree: Subtree,
    legs: list[int],
    forward: FloatArray,
) -> bool:
    """Whether both legs' knees, flexing, move their foot forward (so ``forward`` is the robot's back).

    Args:
        model: The robot model; ``data`` holds its placements at the standing posture.
        data: The model's data, placements computed.
        children: Each joint's child joints.
        subtree: A joint and every joint below it.
        legs: The first joint of each leg.
        forward: (3,) the guessed forward direction, world, horizontal.

    Example:
        >>> knees_face_back(model, data, tree.children, tree.subtree, legs, bearing.forward)
        False

    """
    votes = [_knee_vote(model, data, children, subtree, leg, forward) for leg in legs]
    return bool(votes) and all(v < 0 for v in votes)


def _knee_vote(
    model: pin.Model, data: pin.Data, children: dict[int, list[int]], subtree: Subtree, leg: int, forward: FloatArray
) -> int:
    """+1: the knee's flexion moves the foot backwards (``forward`` agrees); -1: forwards; 0: no clear say."""
    foot = foot_joint(model, leg, children, subtree)
    knee = knee_of(model, data, joint_path(model, leg, foot), forward)
    joint = model.joints[knee]
    if joint.nq != 1:
        return 0
    lower, upper = float(model.lowerPositionLimit[joint.idx_q]), float(model.upperPositionLimit[joint.idx_q])
    large, small = max(upper, -lower), max(min(upper, -lower), 0.0)
    if large < ONE_SIDED * small or large <= 0.0:
        return 0
    axis = data.oMi[knee].rotation @ joint_axis(joint) * (1.0 if upper > -lower else -1.0)  # flexion, world
    moved = np.cross(axis, data.oMi[foot].translation - data.oMi[knee].translation)
    moved[2] = 0.0
    along = float(moved @ forward)
    if abs(along) < CLEAR * float(np.linalg.norm(moved)):
        return 0
    return 1 if along < 0 else -1
