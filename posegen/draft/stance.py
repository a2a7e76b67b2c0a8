"""How a robot stands, found from its description alone (``posegen robot init``).

* up: of the six root axes, the one along which exactly two branches alike in mass reach
  the lowest level (the legs) with the centre of mass highest above it; the root is
  turned so that it points up (``stance.root_rpy_deg`` for a y-up model). The legs are
  two branches of the root, else of the branching joint found by descending from the
  root into its only branch reaching the floor (a torso-rooted model: waist joints down
  to a pelvis, :func:`reaching_branches`);
* forward: the root's x axis (REP 103, and the biomechanics convention of y-up models),
  left: up x forward;
* soles: :mod:`posegen.draft.soles`;
* the reference posture, when no SRDF gives one: soles flat where they stand, pelvis
  lowered so that the knees bend, CoM over the middle of the feet.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError
from posegen.robot import FloatArray

FLOOR_TOL_M = 0.02  # a branch whose lowest frame is this close to the lowest one reaches the floor
KNEE_START_RAD = 0.4
CROUCH = 0.03  # the pelvis is lowered by this share of the leg's length at the reference
IK_TOL = 1e-9
LEG_MASS_RATIO = 0.5  # two legs weigh alike within this ratio
LIMIT_MARGIN_RAD = 0.05  # the bent legs keep this far inside their joints' limits


Subtree = Callable[[int], list[int]]


def find_up(
    model: pin.Model, q: FloatArray, children: dict[int, list[int]], subtree: Subtree, label: str
) -> tuple[pin.SE3, str]:
    """The root's orientation that puts the model's up axis up, and that axis.

    Args:
        model: The robot model (joint 1 is the free-flyer root).
        q: (nq,) the posture to turn.
        children: Each joint's child joints.
        subtree: A joint and every joint below it.
        label: The model, named in errors.

    Raises:
        ConfigError: No axis along which two branches of one joint, alike in mass, reach the
            floor (one leg, no legs), or an axis along which four or more do (a quadruped).

    """
    if not children.get(1):
        raise ConfigError(f"{label}: no joint below its root link: posegen needs a humanoid with two legs and two arms")
    data = model.createData()
    best: tuple[float, pin.SE3, str] | None = None
    for axis in range(3):
        for sign in (1.0, -1.0):
            u = np.zeros(3)
            u[axis] = sign
            rotation = pin.Quaternion.FromTwoVectors(u, np.array([0.0, 0.0, 1.0])).toRotationMatrix()
            if sign < 0 and axis == 2:
                rotation = pin.rpy.rpyToMatrix(np.pi, 0.0, 0.0)
            root = pin.SE3(rotation, np.zeros(3))
            qq = q.copy()
            qq[:7] = pin.SE3ToXYZQUAT(root)
            pin.framesForwardKinematics(model, data, qq)
            lowest = {b: min(_heights(model, data, set(subtree(b)))) for b in range(2, model.njoints)}
            floor = min(lowest[b] for b in children[1])
            reaching = reaching_branches(children, lowest, floor)
            name = f"{'+' if sign > 0 else '-'}{'xyz'[axis]}"
            if len(reaching) >= 4 and _alike(model, subtree, reaching):
                raise ConfigError(
                    f"{label}: {len(reaching)} limbs alike in mass reach the floor along the root's {name} axis: "
                    "a robot on four legs, not a humanoid; posegen needs a humanoid with two legs"
                )
            if len(reaching) != 2 or not _alike(model, subtree, reaching):
                continue
            if model.parents[reaching[0]] != 1 and len(upper_branches(model, children, reaching)) < 2:
                continue  # legs below the root leave the arms: else a legless model stands on its arms
            com = float(pin.centerOfMass(model, data, qq)[2]) - floor
            if best is None or com > best[0]:
                best = (com, root, name)
    if best is None:
        names = ", ".join(f"'{model.names[b]}'" for b in children[1])
        raise ConfigError(
            f"{label}: no two legs: along no axis do exactly two branches of the root ({names}), or of a joint "
            "below its only branch reaching the floor, alike in mass reach the floor; posegen needs a humanoid "
            "with two legs"
        )
    return best[1], best[2]


def reaching_branches(children: dict[int, list[int]], lowest: dict[int, float], floor: float) -> list[int]:
    """The branches reaching the floor at the branching joint: the root's, else below its only reaching branch.

    From the root down: where exactly one branch of a joint reaches the floor, the legs are
    below it (waist joints down to a pelvis); the first joint with none or several reaching
    branches is the branching joint.

    Args:
        children: Each joint's child joints (joint 1: the root).
        lowest: Each joint's subtree's lowest height (m).
        floor: The lowest height (m).

    Example:
        >>> reaching_branches({1: [2, 5], 2: [3, 4], 3: [], 4: [], 5: []}, {2: 0.0, 3: 0.0, 4: 0.01, 5: 1.0}, 0.0)
        [3, 4]

    """
    joint = 1
    while True:
        reaching = [b for b in children[joint] if lowest[b] < floor + FLOOR_TOL_M]
        if len(reaching) != 1:
            return reaching
        joint = reaching[0]


def upper_branches(model: pin.Model, children: dict[int, list[int]], legs: list[int]) -> list[int]:
    """The upper body's branches: of the root and of each joint down to the legs' branching joint, those off the legs.

    Example:
        >>> upper_branches(model, tree.children, legs.roots)  # the shoulders (and the neck)
        [12, 13, 18]

    """
    path = [1, *waist_joints(model, legs)]  # the root down to the branching joint
    on_path = set(path) | set(legs)
    return sorted(c for j in path for c in children[j] if c not in on_path)


def waist_joints(model: pin.Model, legs: list[int]) -> list[int]:
    """The joints from the root down to the legs' branching joint (their parent), root side first; none at the root.

    Example:
        >>> waist_joints(model, legs.roots)  # a torso root, two waist joints down to the pelvis
        [2, 3]

    """
    out = []
    joint = int(model.parents[legs[0]])
    while joint > 1:  # 1: the free-flyer root
        out.append(joint)
        joint = int(model.parents[joint])
    return out[::-1]


def joint_path(model: pin.Model, first: int, last: int) -> list[int]:
    """Joints from ``first`` down to ``last`` (its descendant), both included.

    Example:
        >>> joint_path(model, legs.roots[0], foot)  # hip to ankle
        [2, 3, 4, 5, 6, 7]

    """
    out = [last]
    while out[-1] != first:
        out.append(int(model.parents[out[-1]]))
    return out[::-1]


def _alike(model: pin.Model, subtree: Subtree, branches: list[int]) -> bool:
    """Whether two branches weigh alike (within LEG_MASS_RATIO): a pair of legs, not a leg and a torso."""
    masses = [sum(model.inertias[j].mass for j in subtree(b)) for b in branches]
    return min(masses) >= LEG_MASS_RATIO * max(masses)


def _heights(model: pin.Model, data: pin.Data, joints: set[int]) -> list[float]:
    frames = [f for f in range(len(model.frames)) if model.frames[f].parentJoint in joints]
    return [float(data.oMf[f].translation[2]) for f in frames] + [float(data.oMi[j].translation[2]) for j in joints]


def foot_joint(model: pin.Model, leg: int, children: dict[int, list[int]], subtree: Subtree) -> int:
    """The last joint of a leg: down its heaviest branch."""
    joint = leg
    while children[joint]:
        joint = max(children[joint], key=lambda c: sum(model.inertias[j].mass for j in subtree(c)))
    return joint


def knee_of(model: pin.Model, data: pin.Data, leg: list[int], forward: FloatArray) -> int:
    """The knee: of the leg joints farthest from both its ends, the one whose axis is most lateral."""
    hip, ankle = data.oMi[leg[0]].translation, data.oMi[leg[-1]].translation
    lateral = np.cross([0.0, 0.0, 1.0], forward)

    def middle(j: int) -> float:
        p = data.oMi[j].translation
        return min(float(np.linalg.norm(p - hip)), float(np.linalg.norm(p - ankle)))

    turning = [j for j in leg if model.joints[j].shortname().startswith("JointModelR")] or leg  # a knee turns
    far = max(middle(j) for j in turning)
    near_middle = [j for j in turning if middle(j) > far - 0.01]
    return max(near_middle, key=lambda j: abs(float(data.oMi[j].rotation @ joint_axis(model.joints[j]) @ lateral)))


def bend_legs(
    model: pin.Model, q: FloatArray, legs: list[list[int]], soles: list[pin.SE3], forward: FloatArray, leg_length: float
) -> FloatArray | None:
    """The reference with the pelvis lowered (knees bent), soles flat where they stood, CoM between the feet.

    Args:
        model: The robot model.
        q: (nq,) the straight posture, root placed.
        legs: Each leg's joints, hip to foot.
        soles: Each sole's world pose in ``q``, parented to the leg's last joint.
        forward: (3,) world forward direction.
        leg_length: m.

    Returns:
        (nq,) the bent posture, or None when the legs cannot reach (limits).

    """
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    local = [data.oMi[leg[-1]].actInv(s) for leg, s in zip(legs, soles, strict=True)]  # sole in foot joint frame
    out = q.copy()
    starts = []
    for leg in legs:
        knee = knee_of(model, data, leg, forward)
        starts.append((knee, _knee_start(model, data, knee, leg[-1], forward)))
    shift = np.array([0.0, 0.0, CROUCH * leg_length])  # soles rise relative to the root = root lowered
    for _ in range(4):  # CoM correction: move the soles under the CoM
        targets = [pin.SE3(s.rotation, s.translation + shift) for s in soles]
        for leg, target, offset, start in zip(legs, targets, local, starts, strict=True):
            if not _bend(model, out, q, leg, target * offset.inverse(), start):
                return None
        pin.framesForwardKinematics(model, data, out)
        com = pin.centerOfMass(model, data, out)
        middle = np.mean([t.translation for t in targets], axis=0)
        error = com[:2] - middle[:2]
        if np.linalg.norm(error) < 1e-3:
            break
        shift[:2] += error
    return out


def _bend(
    model: pin.Model, out: FloatArray, straight: FloatArray, leg: list[int], target: pin.SE3, start: tuple[int, float]
) -> bool:
    """Reach ``target`` with a leg from the knee bent forward, else (limits) backward. ``out`` is changed in place."""
    knee, angle = start
    for sign in (1.0, -1.0):
        trial = out.copy()
        if abs(out[model.joints[knee].idx_q] - straight[model.joints[knee].idx_q]) < 1e-12 or sign < 0:
            trial[[model.joints[j].idx_q for j in leg]] = straight[[model.joints[j].idx_q for j in leg]]
            trial[model.joints[knee].idx_q] = sign * angle
        if _reach(model, trial, leg, target):
            out[:] = trial
            return True
    return False


def _knee_start(model: pin.Model, data: pin.Data, knee: int, foot: int, forward: FloatArray) -> float:
    """A starting knee angle that moves the foot backwards, within the joint's limits."""
    axis = data.oMi[knee].rotation @ joint_axis(model.joints[knee])
    lever = data.oMi[foot].translation - data.oMi[knee].translation
    backwards = -float(np.cross(axis, lever) @ forward)  # d(foot)/d(angle) . (-forward)
    i = model.joints[knee].idx_q
    lower, upper = float(model.lowerPositionLimit[i]), float(model.upperPositionLimit[i])
    angle = KNEE_START_RAD if backwards >= 0 else -KNEE_START_RAD
    return float(np.clip(angle, lower, upper))


def joint_axis(joint: pin.JointModel) -> FloatArray:
    """A 1-dof joint's axis (of rotation or of translation) in its own frame. Shape (3,)."""
    name = joint.shortname()
    if name[:11] in ("JointModelR", "JointModelP") and name[-1] in "XYZ" and "Unaligned" not in name:
        out = np.zeros(3)
        out["XYZ".index(name[-1])] = 1.0
        return out
    return np.asarray(joint.extract().axis, dtype=float)


def _reach(model: pin.Model, q: FloatArray, leg: list[int], target: pin.SE3) -> bool:
    """Move a leg's joints (in place) so that its last joint reaches ``target``, within their limits.

    Bounded least squares (scipy's trust region reflective) on the pose error.
    """
    from scipy.optimize import least_squares

    data = model.createData()
    rows = [model.joints[j].idx_q for j in leg]
    lower = model.lowerPositionLimit[rows] + LIMIT_MARGIN_RAD
    upper = model.upperPositionLimit[rows] - LIMIT_MARGIN_RAD
    if np.any(lower >= upper):
        return False
    trial = q.copy()

    def error(x: FloatArray) -> FloatArray:
        trial[rows] = x
        pin.forwardKinematics(model, data, trial)
        return np.asarray(pin.log6(data.oMi[leg[-1]].actInv(target)).vector)

    start = np.clip(q[rows], lower, upper)
    fit = least_squares(error, start, bounds=(lower, upper), method="trf", xtol=1e-12, ftol=1e-12, gtol=1e-12)
    if float(fit.fun @ fit.fun) > IK_TOL:
        return False
    q[rows] = fit.x
    return True
