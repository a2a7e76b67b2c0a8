"""The force a drafted hand presses the table with (``route.contact_force_n``): what its wrists can hold.

posegen plans every contact within ``margins.effort_ratio`` of the URDF's effort limits,
the hand pressing ``route.contact_force_n`` (30 N unless the config says otherwise). A
robot with small wrists (some hold 0.45-0.65 N m) cannot press 30 N anywhere: its pool
would find no posture. The draft therefore estimates, for each arm joint, the lever of
the table's reaction about its axis at random arm postures (the contact's normal fixed in
the hand). When some joint cannot hold posegen's default press at its median lever, the
draft presses half of what that joint holds there; the other half is left to the arm's
own weight and the CoM's uncertainty, and to the postures whose lever is longer.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.draft.stance import joint_axis
from posegen.robot import FloatArray, FrameConfig, MarginConfig, RouteConfig

DEFAULT_FORCE_N = RouteConfig.contact_force_n  # posegen's default press (N)
EFFORT_RATIO = MarginConfig.effort_ratio  # the drafted margins.effort_ratio (the default)
PRESS_SHARE = 0.5  # a lowered press: this share of what the weakest joint holds at its median lever
POSTURES = 200  # random arm postures the levers are taken over
SEED = 0


@dataclass(frozen=True)
class HeldForce:
    """The force drafted for the press, and the joint that limits it."""

    force_n: float  # route.contact_force_n to draft (DEFAULT_FORCE_N when the arms hold it)
    joint: str  # the limiting joint ("" when the default holds)
    effort_nm: float  # its URDF effort limit (N m)
    lever_m: float  # its median lever (m)

    @property
    def holds_n(self) -> float:
        """What the limiting joint holds at its median lever (N)."""
        return EFFORT_RATIO * self.effort_nm / self.lever_m if self.lever_m > 0 else np.inf

    @property
    def lowered(self) -> bool:
        """Whether the draft presses less than posegen's default."""
        return self.force_n < DEFAULT_FORCE_N

    @property
    def checks(self) -> tuple[str, ...]:
        """The draft's ``# CHECK:`` line for a lighter press (none for the default)."""
        if not self.lowered:
            return ()
        return (
            f"route.contact_force_n {self.force_n:g} N, not posegen's {DEFAULT_FORCE_N:g} N: '{self.joint}' "
            f"(URDF effort {self.effort_nm:g} N m, x margins.effort_ratio) holds {self.holds_n:.0f} N at its median "
            f"lever ({1e3 * self.lever_m:.0f} mm), and the draft presses {PRESS_SHARE:.0%} of that; check the "
            "wrists' limits, and that the wrist sensor resolves this force (recording.force_threshold_n is half of it)",
        )


def held_force(
    model: pin.Model, q: FloatArray, arms: list[tuple[tuple[str, ...], tuple[FrameConfig, ...], bool]]
) -> HeldForce:
    """The default press if every arm joint holds it at its median lever, else half what the weakest holds (N).

    Args:
        model: The robot model.
        q: (nq,) the reference posture; each arm's joints are drawn uniformly within their limits.
        arms: Per arm its joints' names, its contact frames and whether the contact is flush (the
            table's normal is then the hand's up at ``q``; a point contact's is its frame's z).

    Example:
        >>> held = held_force(model, body.reference, [(c.joints, c.contact.frames, c.contact.flush) for c in chains])
        >>> held.force_n, held.joint  # a robot with 0.65 N m wrists
        (10.0, 'left_wrist_3')

    """
    weakest = (np.inf, "", 0.0, 0.0)  # (the force the median posture holds (N), joint, effort (N m), lever (m))
    for names, frames, flush in arms:
        joints = [model.getJointId(n) for n in names]
        levers = _levers(model, q, joints, frames, flush)  # (POSTURES, len(joints)) m
        for k, j in enumerate(joints):
            effort = float(model.effortLimit[model.joints[j].idx_v])
            lever = float(np.median(levers[:, k]))
            if effort > 0.0 and lever > 0.0:  # no effort limit: unchecked (the draft says so elsewhere)
                weakest = min(weakest, (EFFORT_RATIO * effort / lever, str(model.names[j]), effort, lever))
    holds, joint, effort, lever = weakest
    if holds >= DEFAULT_FORCE_N:
        return HeldForce(DEFAULT_FORCE_N, "", 0.0, 0.0)
    return HeldForce(max(float(np.floor(PRESS_SHARE * holds)), 1.0), joint, effort, lever)


def _levers(
    model: pin.Model, q: FloatArray, joints: list[int], frames: tuple[FrameConfig, ...], flush: bool
) -> FloatArray:
    """(POSTURES, len(joints)) m: each joint's largest lever of a unit normal force at the contact frames."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    placed = [
        (model.getFrameId(f.parent), pin.SE3(pin.rpy.rpyToMatrix(*np.deg2rad(f.rpy_deg)), np.array(f.xyz_m)))
        for f in frames
    ]
    parent = placed[0][0]
    up = np.array([0.0, 0.0, 1.0])
    normal = data.oMf[parent].rotation.T @ up if flush else placed[0][1].rotation @ up  # (3,) in the hand's frame
    rng = np.random.default_rng(SEED)
    index = [model.joints[j].idx_q for j in joints]
    out = np.zeros((POSTURES, len(joints)))
    for s in range(POSTURES):
        posture = np.array(q, dtype=float)
        posture[index] = rng.uniform(model.lowerPositionLimit[index], model.upperPositionLimit[index])
        pin.framesForwardKinematics(model, data, posture)
        points = [(data.oMf[f] * local).translation for f, local in placed]  # (3,) m each, world
        n = data.oMf[parent].rotation @ normal  # (3,) world
        for k, j in enumerate(joints):
            axis, origin = data.oMi[j].rotation @ joint_axis(model.joints[j]), data.oMi[j].translation
            kind = model.joints[j].shortname()
            if kind.startswith("JointModelP") and not kind.startswith("JointModelPlanar"):
                out[s, k] = abs(float(axis @ n))  # a slide: the force along its axis
            else:
                out[s, k] = max(abs(float(axis @ np.cross(p - origin, n))) for p in points)
    return out
