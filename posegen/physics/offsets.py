"""Joint offsets from frame twists: the legs move the soles, the arms the hands, each relative to the base.

The stabilizer asks each sole, and the contact controllers each hand, to move relative
to the base by a twist; the offset ``dq`` (nj,) rad added to the planned angles is
integrated from them on the nominal model's Jacobians at the encoders' angles: a sole's
twist by its leg's joints (from the sole up to the joint both legs hang from), a hand's
by its arm's own joints (its chain's, less the legs' and those another chain shares:
the torso stays as planned). Locked joints never move.
"""

from __future__ import annotations

import numpy as np

from posegen.model import ChainModel
from posegen.physics.nominal import NominalRobot
from posegen.robot import FloatArray, Scene

DAMPING = 1e-4  # of the least-squares solves (m^2: a few centimetres of damping near singularities)
NULL_DECAY_S = 10.0  # an arm's offset that moves no task decays back to the plan (slowly: a hold stays still)


def arm_joints(scene: Scene) -> dict[str, list[int]]:
    """Each chain's own arm joints (indices in the scene's joints): its chain's, less the legs' and shared ones."""
    chains = {c.name: set(ChainModel(scene, c.name).joint_indices) for c in scene.chains}
    legs = set(scene.stance_leg_joints())
    out = {}
    for name, joints in chains.items():
        shared = set().union(*(other for key, other in chains.items() if key != name))
        out[name] = sorted(j for j in joints - legs - shared if not scene.locked[j])
    return out


class JointOffsets:
    """Integrates the joint offset ``dq`` from the soles' and the hands' twists relative to the base.

    Example:
        >>> offsets = JointOffsets(scene, robot)
        >>> dq = offsets.step(sole_twists, hand_twists, dt_s=0.002)

    """

    def __init__(self, scene: Scene, robot: NominalRobot) -> None:
        self.robot = robot
        self.dq = np.zeros(len(scene.joint_names))
        self.legs = [[j for j in scene.leg_joints(s) if not scene.locked[j]] for s in scene.stance.sole_frames]
        self.arms = arm_joints(scene)

    def _solve(self, frame: int, joints: list[int], twist: FloatArray, decay: bool = True) -> FloatArray:
        """Joint rates (len(joints),) that move a frame by ``twist`` (6,) relative to the base.

        Damped least squares; a redundant chain's offset that moves no task decays toward zero
        (its self-motion would otherwise drift).
        """
        jacobian = self.robot.frame_jacobian(frame)[:, 6 + np.asarray(joints)]  # (6, n)
        if jacobian.shape[1] < 6:
            return np.asarray(
                np.linalg.solve(jacobian.T @ jacobian + DAMPING * np.eye(len(joints)), jacobian.T @ twist)
            )
        gram = jacobian @ jacobian.T + DAMPING * np.eye(6)
        if not decay:
            return np.asarray(jacobian.T @ np.linalg.solve(gram, twist))
        decaying = self.dq[joints] / NULL_DECAY_S  # its part no task needs decays: -(I - J+ J) dq / T
        return np.asarray(jacobian.T @ np.linalg.solve(gram, twist + jacobian @ decaying) - decaying)

    def step(
        self, soles: list[FloatArray], hands: dict[str, FloatArray], dt_s: float, decay: bool = True
    ) -> FloatArray:
        """Advance the offset by one control period; the robot updated at the encoders' angles.

        Args:
            soles: Each sole's twist (6,) relative to the base, world axes at the sole (stance order).
            hands: Chain -> its hand's twist (6,) relative to the base, world axes at its contact frame.
            dt_s: Control period, s.
            decay: Let the arms' unused offsets decay (not while a hand is at the table: a
                contact is measured with every joint still).

        Returns:
            The joint offset (nj,) rad to add to the planned angles.

        """
        robot = self.robot
        for frame, leg, twist in zip(robot.soles, self.legs, soles, strict=True):
            if np.any(twist):
                self.dq[leg] += dt_s * self._solve(frame, leg, twist)
        for chain, twist in hands.items():
            arm = self.arms[chain]
            if np.any(twist) or (decay and np.any(self.dq[arm])):
                self.dq[arm] += dt_s * self._solve(robot.contact_frames[chain], arm, twist, decay)
        return self.dq
