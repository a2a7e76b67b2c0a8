"""Joint limits as ``posegen robot init`` reads them: implausible speeds, postures at or past a limit.

And the reference's joints moved clear of their limits, or locked within them.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from posegen.robot import FloatArray

IMPLAUSIBLE_SPEED_RAD_S = 50.0  # humanoid joints turn at up to ~40 rad/s (small wrist motors); above, a stand-in
PLACEHOLDER_SPEED_RAD_S = 3.0  # a humanoid joint's usual speed limit (TALOS: 2.7-6.3 rad/s), where the URDF has none
JOINT_LIMIT_MARGIN_RAD = 0.02  # the drafted margins.joint_limit_rad
COM_MARGIN_M = 0.02  # the drafted margins.com_m
LIMIT_CLEARANCE_RAD = 0.05  # the reference keeps free joints this far inside their limits


def velocity_placeholders(model: pin.Model, kept: set[int]) -> tuple[dict[str, float], dict[str, float]]:
    """Placeholder speeds (rad/s) for the kept joints whose URDF speed is 0 or implausible, and the URDF's.

    A URDF's speed up to ``IMPLAUSIBLE_SPEED_RAD_S`` is kept; none (0, an MJCF without
    limits) or a larger one (a description's stand-in, as iCub's 100 rad/s on every joint)
    gets ``PLACEHOLDER_SPEED_RAD_S``, which the draft says in a ``# CHECK:`` line.
    """
    speeds: dict[str, float] = {}
    urdf_speed: dict[str, float] = {}
    for j in sorted(kept - {1}):
        if model.joints[j].nq != 1:
            continue
        v = float(model.velocityLimit[model.joints[j].idx_v])
        if not 0 < v <= IMPLAUSIBLE_SPEED_RAD_S:
            speeds[str(model.names[j])] = PLACEHOLDER_SPEED_RAD_S
            urdf_speed[str(model.names[j])] = v
    return speeds, urdf_speed


def missing_efforts(model: pin.Model, kept: set[int], locked: set[str]) -> list[str]:
    """The kept, unlocked 1-dof joints whose URDF gives no effort limit (0): their torques go unchecked."""
    out = []
    for j in sorted(kept - {1}):
        name = str(model.names[j])
        if model.joints[j].nq == 1 and name not in locked and not model.effortLimit[model.joints[j].idx_v] > 0:
            out.append(name)
    return out


def limits(model: pin.Model, joint: int) -> tuple[float, float]:
    """A 1-dof joint's limits (rad)."""
    i = model.joints[joint].idx_q
    return float(model.lowerPositionLimit[i]), float(model.upperPositionLimit[i])


def near_limit(model: pin.Model, q: FloatArray, joint: int) -> bool:
    """Whether a joint of ``q`` (nq,) is within the drafted margin of a limit."""
    low, high = limits(model, joint)
    value = float(q[model.joints[joint].idx_q])
    return min(value - low, high - value) < JOINT_LIMIT_MARGIN_RAD


def outside_limits(model: pin.Model, q: FloatArray) -> list[str]:
    """The 1-dof joints of a configuration outside their limits."""
    return [
        str(model.names[j])
        for j in range(2, model.njoints)
        if model.joints[j].nq == 1 and not limits(model, j)[0] <= q[model.joints[j].idx_q] <= limits(model, j)[1]
    ]


def without_room(model: pin.Model, joints: set[int], margin_rad: float) -> tuple[set[int], tuple[str, ...]]:
    """The 1-dof joints of ``joints`` whose limits leave no room inside ``margin_rad`` of each (lower = upper).

    The plan keeps every free joint ``margins.joint_limit_rad`` inside its limits, so such a
    joint is locked: returned with a ``# CHECK:`` line each.

    Example:
        >>> without_room(model, {model.getJointId("arm_left_3_joint")}, 0.02)[0]  # doctest: +SKIP
        {4}

    """
    stuck = {j for j in joints if model.joints[j].nq == 1 and np.diff(limits(model, j))[0] <= 2 * margin_rad}
    checks = tuple(
        f"'{model.names[j]}' has no room between its limits [{limits(model, j)[0]:g}, {limits(model, j)[1]:g}] rad "
        f"(margins.joint_limit_rad {margin_rad:g} inside each): locked; check its limits in the URDF"
        for j in sorted(stuck)
    )
    return stuck, checks


def locked_joints(model: pin.Model, q: FloatArray, kept: set[int]) -> dict[str, float]:
    """Every 1-dof joint not kept, at its value in ``q`` (nq,) brought within its limits (rad)."""
    return {
        str(model.names[j]): float(np.clip(q[model.joints[j].idx_q], *limits(model, j)))
        for j in range(2, model.njoints)
        if model.joints[j].nq == 1 and j not in kept
    }


def clear_of_limits(model: pin.Model, q: FloatArray, joints: list[int]) -> dict[str, float]:
    """The joints of ``joints`` that ``q`` (nq,) puts too near a limit, moved clear of it (rad)."""
    out = {}
    for j in joints:
        low, high = limits(model, j)
        value = float(q[model.joints[j].idx_q])
        inside = float(np.clip(value, low + LIMIT_CLEARANCE_RAD, high - LIMIT_CLEARANCE_RAD))
        if low + LIMIT_CLEARANCE_RAD <= high - LIMIT_CLEARANCE_RAD and inside != value:
            out[str(model.names[j])] = inside
    return out


def with_joints(model: pin.Model, q: FloatArray, values: dict[str, float]) -> FloatArray:
    """A copy of ``q`` (nq,) with these joints (1-dof, by name) set (rad)."""
    out = np.array(q, dtype=float)
    for name, value in values.items():
        out[model.joints[model.getJointId(name)].idx_q] = value
    return out
