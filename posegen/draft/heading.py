"""Which way a drafted humanoid faces: its root's x axis, unless both knees say another root axis.

URDFs name no "forward". The draft takes the root's x axis (REP 103), which most humanoids
follow; some roots point elsewhere (iCub's root x axis points behind the robot; a model
exported with y forward). A knee whose range is clearly one-sided bends the shank
backwards, so the foot moves behind the knee when it flexes: when both knees say so, the
draft faces the level root axis nearest their forward (and so turns its left and right,
its table side), and says so.
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
    "the robot faces its root's {axis} axis (both knees bend that way): forward, left and right, and the table's "
    "side are taken from there; check with `posegen view`"
)
LEVEL = 0.9  # a root axis is a candidate forward when its level part is this long (the others point up or down)
SAME = 0.999  # cosine above which two directions are the same


@dataclass(frozen=True, eq=False)
class Bearing:
    """How the robot is turned: its root's pose, the up axis, and the horizontal directions."""

    root: pin.SE3  # the root's pose (its orientation puts the up axis up)
    up: str  # the root's axis pointing up, e.g. "+z"
    forward: FloatArray  # (3,) world, horizontal
    left: FloatArray  # (3,) world, up x forward
    heading: pin.SE3  # the yaw of forward, at the origin

    def facing(self, forward: FloatArray) -> Bearing:
        """The same root, facing the level direction ``forward`` (3,), left turned with it."""
        left = np.cross([0.0, 0.0, 1.0], forward)
        if float(forward @ self.forward) < -SAME:  # turned around: the exact opposites
            forward, left = -self.forward, -self.left
        heading = pin.SE3(yaw_rotation(float(np.arctan2(forward[1], forward[0]))), np.zeros(3))
        return Bearing(self.root, self.up, forward, left, heading)

    def root_axis(self) -> str:
        """The root's axis that points forward, e.g. "-x"."""
        along = self.root.rotation.T @ self.forward  # (3,) forward in the root's frame
        i = int(np.argmax(np.abs(along)))
        return f"{'+' if along[i] > 0 else '-'}{'xyz'[i]}"


def forward_of(root: pin.SE3) -> FloatArray:
    """The robot's forward direction in the world: its root's x axis, levelled. Shape (3,)."""
    for column in (0, 2, 1):
        v = root.rotation[:, column].copy()
        v[2] = 0.0
        if np.linalg.norm(v) > 0.5:
            return np.asarray(v / np.linalg.norm(v))
    return np.array([1.0, 0.0, 0.0])


def knees_forward(
    model: pin.Model,
    data: pin.Data,
    children: dict[int, list[int]],
    subtree: Subtree,
    legs: list[int],
    bearing: Bearing,
) -> Bearing:
    """``bearing`` facing the level root axis both knees say is forward (unchanged without a clear say).

    Each knee with a clearly one-sided range moves its foot backwards when it flexes; both
    legs must say so, within ``CLEAR`` of each other, and a level root axis must lie within
    ``CLEAR`` of the forward they say.

    Args:
        model: The robot model; ``data`` holds its placements at the standing posture.
        data: The model's data, placements computed.
        children: Each joint's child joints.
        subtree: A joint and every joint below it.
        legs: The first joint of each leg.
        bearing: The bearing guessed from the root's x axis.

    Example:
        >>> knees_forward(model, data, tree.children, tree.subtree, legs, bearing).root_axis()
        '+x'

    """
    motions = [_flexion_motion(model, data, children, subtree, leg, bearing.forward) for leg in legs]
    backs = [m for m in motions if m is not None]
    if not backs or len(backs) < len(legs) or float(backs[0] @ backs[-1]) < CLEAR:
        return bearing
    said = -np.sum(backs, axis=0)
    said /= np.linalg.norm(said)
    candidates = [s * bearing.root.rotation[:, i] * [1.0, 1.0, 0.0] for i in range(3) for s in (1.0, -1.0)]
    level = [c / np.linalg.norm(c) for c in candidates if np.linalg.norm(c) > LEVEL]
    best = max(level, key=lambda c: float(c @ said))
    if float(best @ said) < CLEAR or float(best @ bearing.forward) > SAME:
        return bearing
    return bearing.facing(best)


def _flexion_motion(
    model: pin.Model, data: pin.Data, children: dict[int, list[int]], subtree: Subtree, leg: int, guess: FloatArray
) -> FloatArray | None:
    """The level direction (3,) a leg's foot moves when its knee flexes; None: no one-sided knee, or no level motion.

    ``guess`` (3,) is the forward guessed so far: it tells the knee from other joints midway down the leg.
    """
    foot = foot_joint(model, leg, children, subtree)
    knee = knee_of(model, data, joint_path(model, leg, foot), guess)
    joint = model.joints[knee]
    if joint.nq != 1:
        return None
    lower, upper = float(model.lowerPositionLimit[joint.idx_q]), float(model.upperPositionLimit[joint.idx_q])
    large, small = max(upper, -lower), max(min(upper, -lower), 0.0)
    if large < ONE_SIDED * small or large <= 0.0:
        return None
    axis = data.oMi[knee].rotation @ joint_axis(joint) * (1.0 if upper > -lower else -1.0)  # flexion, world
    moved = np.cross(axis, data.oMi[foot].translation - data.oMi[knee].translation)
    moved[2] = 0.0
    norm = float(np.linalg.norm(moved))
    return moved / norm if norm > 0.0 else None
