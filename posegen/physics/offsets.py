"""Joint offsets from frame twists: the legs move the soles, the arms the hands, each relative to the base.

The stabilizer asks each sole, and the contact controllers each hand, to move relative
to the base by a twist; the offset ``dq`` (nj,) rad added to the planned angles is
integrated from them on the nominal model's Jacobians at the encoders' angles: a sole's
twist by its leg's joints (from the sole up to the joint both legs hang from), both
hands' together by the upper body's joints (every chain's, less the legs': the torso and
the arms; an arm alone, near the end of its reach, cannot move its hand along the table's
normal), the torso's joints weighted ``SHARED_WEIGHT`` times an arm's (the arms move the
hands; the torso, holding the whole upper body, often near its effort limit, helps only
where they cannot). The planned angle plus the offset stays ``LIMIT_MARGIN_RAD`` inside
each joint's limits; a joint held there weighs ``AT_LIMIT_WEIGHT`` times more in the next
solves (the others take its share). Locked joints never move.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from posegen.model import ChainModel
from posegen.physics.lapack import solve
from posegen.physics.nominal import NominalRobot
from posegen.physics.shaping import clamp
from posegen.robot import FloatArray, Scene

DAMPING = 1e-4  # of the least-squares solves (m^2: a few centimetres of damping near singularities)
LIMIT_MARGIN_RAD = 0.005  # the offset keeps the commanded angle this far inside the joint limits
AT_LIMIT_WEIGHT = 400.0  # cost of moving a joint held at its limit, relative to a free one
SHARED_WEIGHT = 10.0  # cost of a torso joint's motion relative to an arm joint's, in the hands' solve
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


def upper_body(scene: Scene) -> list[int]:
    """The joints that move the hands and not the soles: every chain's, less the legs' (torso and arms)."""
    legs = set(scene.stance_leg_joints())
    joints = {j for c in scene.chains for j in ChainModel(scene, c.name).joint_indices}
    return sorted(j for j in joints - legs if not scene.locked[j])


class JointOffsets:
    """Integrates the joint offset ``dq`` from the soles' and the hands' twists relative to the base.

    Example:
        >>> offsets = JointOffsets(scene, robot)
        >>> dq = offsets.step(sole_twists, hand_twists, planned_angles, dt_s=0.002)

    """

    def __init__(self, scene: Scene, robot: NominalRobot) -> None:
        self.robot = robot
        self.dq = np.zeros(len(scene.joint_names))
        self.legs = [[j for j in scene.leg_joints(s) if not scene.locked[j]] for s in scene.stance.sole_frames]
        self.arms = arm_joints(scene)
        self.upper = upper_body(scene)
        own = {j for arm in self.arms.values() for j in arm}
        self.shared = [j for j in self.upper if j not in own]  # the torso
        self._scale = np.ones(len(scene.joint_names))  # a joint's rate per unit of the solve's variable
        self._scale[self.shared] = 1.0 / np.sqrt(SHARED_WEIGHT)
        middle = 0.5 * (scene.lower + scene.upper)
        self._lower = np.minimum(scene.lower + LIMIT_MARGIN_RAD, middle)
        self._upper = np.maximum(scene.upper - LIMIT_MARGIN_RAD, middle)
        self._movable = np.zeros(len(scene.joint_names), dtype=bool)
        self._movable[[j for leg in self.legs for j in leg] + self.upper] = True
        self._at_limit = np.zeros(len(scene.joint_names), dtype=bool)
        self._dampings: dict[int, FloatArray] = {}
        self._indices: dict[tuple[int, ...], NDArray[np.intp]] = {}

    def moving(self, chain: str) -> list[int]:
        """The joints that move a chain's hand: its arm's and the torso's."""
        return self.arms[chain] + self.shared

    def _damping(self, size: int) -> FloatArray:
        """(size, size) the solves' damping, ``DAMPING`` times the identity (kept: do not modify)."""
        if size not in self._dampings:
            self._dampings[size] = DAMPING * np.eye(size)
        return self._dampings[size]

    def _index(self, joints: list[int]) -> NDArray[np.intp]:
        """The joints (scene indices) as an index array, made once per list (numpy indexes faster with one)."""
        key = tuple(joints)
        index = self._indices.get(key)
        if index is None:
            index = self._indices[key] = np.array(joints, dtype=np.intp)
        return index

    def _solve(self, frames: list[int], joints: list[int], twist: FloatArray, decay: bool = True) -> FloatArray:
        """Joint rates (len(joints),) that move frames by ``twist`` (6 per frame,) relative to the base.

        Damped least squares; a redundant chain's offset that moves no task decays toward zero
        (its self-motion would otherwise drift).
        """
        index = self._index(joints)
        scale = np.where(self._at_limit[index], 1.0 / np.sqrt(AT_LIMIT_WEIGHT), 1.0) * self._scale[index]  # (n,)
        blocks = [self.robot.joint_jacobian(f, joints) for f in frames]
        jacobian = (blocks[0] if len(blocks) == 1 else np.vstack(blocks)) * scale
        rows = jacobian.shape[0]  # jacobian (6k, n)
        if jacobian.shape[1] < rows:
            gram = jacobian.T @ jacobian + self._damping(len(joints))
            return np.asarray(scale * solve(gram, jacobian.T @ twist))
        gram = jacobian @ jacobian.T + self._damping(rows)
        if not decay:
            return np.asarray(scale * (jacobian.T @ solve(gram, twist)))
        decaying = self.dq[index] / scale / NULL_DECAY_S  # its part no task needs decays: -(I - J+ J) dq / T
        return np.asarray(scale * (jacobian.T @ solve(gram, twist + jacobian @ decaying) - decaying))

    def _upper_of(self, chains: list[str]) -> list[int]:
        """The joints that move these chains' hands: the torso's and their own arms'."""
        return sorted(set(self.shared).union(*(self.arms[chain] for chain in chains)))

    def step(
        self,
        soles: list[FloatArray],
        hands: dict[str, FloatArray],
        planned: FloatArray,
        dt_s: float,
        decay: bool = True,
        lagging: frozenset[str] = frozenset(),
    ) -> FloatArray:
        """Advance the offset by one control period; the robot updated at the encoders' angles.

        Args:
            soles: Each sole's twist (6,) relative to the base, world axes at the sole (stance order).
            hands: Chain -> its hand's twist (6,) relative to the base, world axes at its contact frame.
            planned: The planned angles (nj,) rad the offset adds to (the limits hold their sum).
            dt_s: Control period, s.
            decay: Let the arms' unused offsets decay (not while a hand is at the table: a
                contact is measured with every joint still).
            lagging: Chains whose arm lags its command at its effort limit. Away from the
                table (``decay``) such an arm is left as it is: its hand holds no pose, and
                the other hand's twist moves the torso and its own arm only.

        Returns:
            The joint offset (nj,) rad to add to the planned angles.

        """
        robot = self.robot
        for frame, leg, twist in zip(robot.soles, self.legs, soles, strict=True):
            if twist.any():
                self.dq[self._index(leg)] += dt_s * self._solve([frame], leg, twist)
        chains = [chain for chain in self.arms if not (decay and chain in lagging)]
        if chains:  # both arms lagging away from the table: the hands' solve rests
            joints = self.upper if len(chains) == len(self.arms) else self._upper_of(chains)
            twist = np.concatenate([hands[chain] for chain in chains])
            index = self._index(joints)
            if twist.any() or (decay and self.dq[index].any()):
                frames = [robot.contact_frames[chain] for chain in chains]
                self.dq[index] += dt_s * self._solve(frames, joints, twist, decay)
        commanded = planned + self.dq
        self._at_limit = self._movable & ((commanded < self._lower) | (commanded > self._upper))
        self.dq = np.where(self._movable, clamp(commanded, self._lower, self._upper) - planned, 0.0)
        return self.dq
