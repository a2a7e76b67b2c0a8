"""Joint torques that hold a standing posture still: gravity, and the hand's contact force.

With both soles on the floor the robot is a closed chain: the floor's wrenches on the
two soles balance the weight and the hand's contact force (six equations), and the
split between the feet is not determined by statics alone. posegen takes the split of
least size (forces in N and moments in N m over a ``MOMENT_ARM_M`` lever weighed alike),
the usual choice when nothing is known about the feet.

Two loads are modelled:

* :func:`gravity_torques`: the weight alone (the arm in contact unloaded), what the
  compliance model of the calibration deflects the joints with;
* :func:`holding_torques`: the weight and, where a chain's hand is in contact, the
  table's normal reaction of ``force_n`` newtons on its contact frame (the force the
  force-controlled contact holds, ``route.contact_force_n``): what the actuators must
  hold, checked against the URDF's effort limits (:func:`effort_ratios`).

A robot is not its model: its true centre of mass may lie some millimetres from the
model's, and the stance legs carry the difference. :meth:`Statics.com_spread` bounds how
far each holding torque moves when the weight acts up to ``margins.com_uncertainty_m``
from the model's CoM in any horizontal direction (a moment on the base, split between the
soles like the weight); the plan keeps ``|torque| + spread`` within the effort margin.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from posegen.robot.geometry import FloatArray
from posegen.robot.scene import Scene

MOMENT_ARM_M = 0.1  # a moment of 1 N m weighs like a force of 10 N in the wrench split


@dataclass(frozen=True)
class TorquePair:
    """The holding torques of one contact posture, the hand unloaded and pressing, and their spread."""

    unloaded: FloatArray  # (nj,) N m, the hand above the table
    pressing: FloatArray  # (nj,) N m, the hand pressing its contact force
    spread: FloatArray  # (nj,) N m, how far either moves with the CoM's uncertainty (Statics.com_spread)


@dataclass(frozen=True)
class LinearTorques:
    """Holding torques of one posture and their derivative with the soles on the floor."""

    torques: FloatArray  # (nj,) N m
    jacobian: FloatArray  # (nj, nj) d torque / d joints, N m/rad (the floating base following the anchor sole)


class Statics:
    """The statics of a scene's robot standing on both soles (pinocchio workspace reused between postures).

    Example:
        >>> statics = Statics(scene)
        >>> tau = statics.torques(scene.reference, "left", 30.0)  # (nj,) N m

    """

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self.model = scene.model
        self.data = scene.model.createData()
        self.soles = [scene.frame_id(frame) for frame in scene.stance.sole_frames]
        self.weight = np.tile([1.0, 1.0, 1.0, MOMENT_ARM_M, MOMENT_ARM_M, MOMENT_ARM_M], len(self.soles))
        self.normal = np.array(scene.table_pose, dtype=float)[:3, 2]  # the table's normal in the world
        self.hands = {c.name: scene.frame_id(c.frame(c.contact_kind)) for c in scene.config.chains}
        self.velocity = scene.velocity_indices()
        self.anchor = scene.frame_id(scene.anchor_sole)
        weight_n = float(np.linalg.norm(scene.model.gravity.linear)) * sum(i.mass for i in scene.model.inertias)
        # (3, 2) world moments of the weight moved 1 m along world x and along y (weight along -z)
        self._moment_per_m = weight_n * np.array([[0.0, -1.0], [1.0, 0.0], [0.0, 0.0]])
        self._placed: FloatArray | None = None  # (nq,) the configuration whose kinematics are in the workspace

    def com_spread(self, joints: FloatArray) -> FloatArray:
        """How far each holding torque moves with the CoM misplaced by ``margins.com_uncertainty_m``. Shape (nj,), N m.

        The weight moved by ``(dx, dy)`` (m, world) puts a moment on the base that the soles
        carry (split at least size, as the weight): the torques change by ``A (dx, dy)``, at
        most ``u (|A_x| + |A_y|)`` for ``|dx|, |dy| <= u``. Zero when the margin is 0.

        Example:
            >>> bound = np.abs(statics.torques(joints, None, 0.0)) + statics.com_spread(joints)

        """
        if self.scene.margins.com_uncertainty_m == 0.0:
            return np.zeros(len(self.velocity))
        q = self.scene.configuration(joints)
        if self._placed is None or not np.array_equal(q, self._placed):
            self._kinematics(q)
        return self._spread(self._sole_rows())

    def _spread(self, soles: _SoleRows) -> FloatArray:
        """(nj,) N m :meth:`com_spread` at the kinematics in the workspace, its soles' rows ``soles``."""
        uncertainty_m = self.scene.margins.com_uncertainty_m
        if uncertainty_m == 0.0:
            return np.zeros(len(self.velocity))
        load = np.zeros((self.model.nv, 2))  # d generalized forces / d (CoM x, y)
        load[3:6] = self.data.oMi[1].rotation.T @ self._moment_per_m  # the base's local frame
        return uncertainty_m * np.abs(soles.held(load)[self.velocity]).sum(axis=1)

    def _sole_rows(self) -> _SoleRows:
        """The soles' Jacobians and the least-size split's matrices at the kinematics in the workspace."""
        contact = np.vstack([pin.getFrameJacobian(self.model, self.data, f, pin.LOCAL) for f in self.soles])
        return _SoleRows(contact, self.weight)

    def torques(self, joints: FloatArray, chain: str | None, force_n: float) -> FloatArray:
        """Holding torques (nj,) N m of one posture (see :func:`holding_torques`)."""
        q = self.scene.configuration(joints)
        return self._wrenches(q, chain, force_n)[0][self.velocity]

    def torque_pair(self, joints: FloatArray, chain: str, force_n: float) -> TorquePair:
        """Holding torques of one posture, the hand unloaded and pressing, and their spread (one kinematics pass).

        The same numbers as :meth:`torques` (``None`` and ``chain``) and :meth:`com_spread`, bit for bit.

        Example:
            >>> pair = statics.torque_pair(joints, "left", 30.0)
            >>> np.abs(pair.pressing) + pair.spread  # (nj,) N m, what the effort limits must hold

        """
        q = self.scene.configuration(joints)
        gravity = self._kinematics(q)
        soles = self._sole_rows()
        pressing = gravity - self._hand_load(chain, force_n)[1]
        return TorquePair(soles.held(gravity)[self.velocity], soles.held(pressing)[self.velocity], self._spread(soles))

    def _hand_load(self, chain: str, force_n: float) -> tuple[pin.Force, FloatArray]:
        """The table's push on ``chain``'s hand (its frame) and its generalized force (nv,), kinematics as placed."""
        hand = self.hands[chain]
        force = pin.Force(self.data.oMf[hand].rotation.T @ (force_n * self.normal), np.zeros(3))
        return force, pin.getFrameJacobian(self.model, self.data, hand, pin.LOCAL).T @ force.vector

    def _kinematics(self, q: FloatArray) -> FloatArray:
        """Placements and Jacobians of ``q`` in the workspace; the generalized gravity (nv,)."""
        model, data = self.model, self.data
        gravity = pin.computeGeneralizedGravity(model, data, q).copy()
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        self._placed = np.array(q, dtype=float)
        return np.asarray(gravity)

    def _wrenches(
        self, q: FloatArray, chain: str | None, force_n: float, gravity: FloatArray | None = None
    ) -> tuple[FloatArray, list[tuple[int, pin.Force]]]:
        """Generalized torques (nv,) and the wrenches on the robot, (frame, wrench in its frame), hand first.

        ``gravity``: the generalized gravity of ``q`` with its kinematics already in the
        workspace (:meth:`_kinematics`); None: computed here.
        """
        load = self._kinematics(q) if gravity is None else gravity  # (nv,) generalized forces the torques balance
        wrenches: list[tuple[int, pin.Force]] = []
        if chain is not None and force_n != 0.0:
            force, generalized = self._hand_load(chain, force_n)
            wrenches.append((self.hands[chain], force))  # the table pushes the hand along its normal
            load = load - generalized
        rows = self._sole_rows()
        soles = rows.wrenches(load)  # least-size wrenches balancing the load
        wrenches.extend((f, pin.Force(soles[6 * k : 6 * k + 6])) for k, f in enumerate(self.soles))
        return load - rows.contact.T @ soles, wrenches

    def linear(self, joints: FloatArray, chain: str | None, force_n: float) -> LinearTorques:
        """Holding torques and their first-order change with the joints (see :func:`linear_torques`)."""
        model, data = self.model, self.data
        q = self.scene.configuration(joints)
        generalized, wrenches = self._wrenches(q, chain, force_n)
        external = [pin.Force.Zero() for _ in range(model.njoints)]
        for frame, wrench in wrenches:
            parent = model.frames[frame].parentJoint
            external[parent] = external[parent] + model.frames[frame].placement.act(wrench)
        derivative = pin.computeStaticTorqueDerivatives(model, data, q, external)  # (nv, nv), wrenches fixed in frames
        if chain is not None and force_n != 0.0:  # the hand's force is fixed in the world: it turns in the hand's frame
            hand, force = wrenches[0]
            jacobian = pin.getFrameJacobian(model, data, hand, pin.LOCAL)  # (6, nv)
            derivative -= jacobian[:3].T @ pin.skew(force.linear) @ jacobian[3:]
        anchor = pin.getFrameJacobian(model, data, self.anchor, pin.LOCAL)  # (6, nv)
        base = -np.linalg.solve(anchor[:, :6], anchor[:, 6:])  # (6, nv - 6) base velocity per joint velocity
        total = derivative[:, 6:] + derivative[:, :6] @ base  # (nv, nv - 6), the soles' wrenches held
        total -= self._split_change(total[:6], wrenches[-len(self.soles) :])
        out = total[np.ix_(self.velocity, self.velocity - 6)]  # (nj, nj)
        return LinearTorques(generalized[self.velocity], out)

    def _split_change(self, base_rows: FloatArray, soles: list[tuple[int, pin.Force]]) -> FloatArray:
        """(nv, nv - 6) the generalized torques' change by the change of the soles' least-size wrenches.

        The split solves ``B s = r`` (``B``: the soles' free-flyer rows, scaled; ``r``: the
        load on the base) at least size. ``B`` depends on the legs only: a sole's free-flyer
        columns are the adjoint of the base in the sole, ``A``, whose change with a joint
        moving the sole by ``z`` (sole frame) is ``-ad(z) A``.
        """
        model, data = self.model, self.data
        jacobians = [pin.getFrameJacobian(model, data, f, pin.LOCAL) for f, _ in soles]  # (6, nv) each
        split = np.hstack([jac[:, :6].T for jac in jacobians]) * self.weight[None, :]  # (6, 6 k)
        scaled = np.concatenate([w.vector for _, w in soles]) / self.weight  # (6 k,) the split now
        gram = split @ split.T
        pseudo = split.T @ np.linalg.inv(gram)  # (6 k, 6) B^+
        moved, blocks = [], []  # the joints that move a sole, and d B / d joint (6, 6 k) for each
        for s, jac in enumerate(jacobians):
            columns = np.flatnonzero(jac[:, 6:].any(axis=0))
            block = np.zeros((len(columns), 6, split.shape[1]))
            block[:, :, 6 * s : 6 * s + 6] = -np.transpose(_ads(jac[:, 6 + columns].T) @ jac[:, :6], (0, 2, 1))
            moved.append(columns)
            blocks.append(block)
        joints, d_split = np.concatenate(moved), np.concatenate(blocks) * self.weight[None, None, :]  # (K, 6, 6 k)
        change = np.einsum("kij,j->ik", d_split, scaled)  # (6, K): d B s per moving joint
        d_load = np.array(base_rows)  # (6, n): the base load's change, d r = d(B s) at fixed s
        d_load[:, joints] += change
        d_scaled = pseudo @ d_load  # (6 k, n): B^+ d r ...
        projector = np.eye(len(scaled)) - pseudo @ split
        lagrange = np.linalg.solve(gram, split @ scaled)
        d_scaled[:, joints] += -pseudo @ change + projector @ np.einsum("kji,j->ik", d_split, lagrange)
        d_wrench = d_scaled * self.weight[:, None]  # (6 k, n)
        contact = np.vstack(jacobians)  # (6 k, nv)
        return np.asarray(contact.T @ d_wrench)


class _SoleRows:
    """The soles' Jacobians (6 k, nv) LOCAL at one posture and the least-size split they define."""

    def __init__(self, contact: FloatArray, weight: FloatArray) -> None:
        self.contact = contact  # (6 k, nv)
        self.weight = weight  # (6 k,) the wrenches' scaling (MOMENT_ARM_M)
        self.split = contact[:, :6].T * weight[None, :]  # (6, 6 k) free-flyer rows, acting on the scaled wrenches
        self.gram = self.split @ self.split.T  # (6, 6)

    def wrenches(self, load: FloatArray) -> FloatArray:
        """(6 k,) or (6 k, m): the soles' least-size wrenches balancing generalized forces ``load`` (nv,) or (nv, m)."""
        scaled = self.split.T @ np.linalg.solve(self.gram, load[:6])
        return np.asarray(scaled * (self.weight if scaled.ndim == 1 else self.weight[:, None]))

    def held(self, load: FloatArray) -> FloatArray:
        """(nv,) or (nv, m): the generalized torques that hold ``load``, the soles carrying the rest."""
        return np.asarray(load - self.contact.T @ self.wrenches(load))


# The spatial cross product's matrix of a motion (linear v first, angular w): [[w x, v x], [0, w x]] as
# (row, column, component of the motion, sign) for its eighteen non-zero entries; each copies one component.
_SKEW = ((0, 1, 2, -1.0), (0, 2, 1, 1.0), (1, 0, 2, 1.0), (1, 2, 0, -1.0), (2, 0, 1, -1.0), (2, 1, 0, 1.0))
_AD_ENTRIES = tuple(
    (row + r0, column + c0, component + offset, sign)
    for r0, c0, offset in ((0, 0, 3), (3, 3, 3), (0, 3, 0))  # w x twice, v x top right
    for row, column, component, sign in _SKEW
)


def _read_only(values: Sequence[float]) -> NDArray[Any]:
    """A constant array (module level: written once, shared by every call)."""
    out = np.array(values)
    out.flags.writeable = False
    return out


_AD_FLAT = _read_only([6 * row + column for row, column, _, _ in _AD_ENTRIES])  # (18,) in the (6, 6) matrix, row-major
_AD_COMPONENT = _read_only([component for _, _, component, _ in _AD_ENTRIES])  # (18,) which of the motion's six
_AD_SIGN = _read_only([sign for _, _, _, sign in _AD_ENTRIES])  # (18,) +-1


def _ads(motions: FloatArray) -> FloatArray:
    """(K, 6, 6) the matrices of the spatial cross products ``motion x`` of (K, 6) motions (linear first).

    One gather for the eighteen non-zero entries (a pool's projection asks for these at
    every torque derivative: 14 us each built block by block, 5 us so).
    """
    out = np.zeros((len(motions), 36))
    out[:, _AD_FLAT] = motions[:, _AD_COMPONENT] * _AD_SIGN
    return out.reshape(len(motions), 6, 6)


def gravity_torques(scene: Scene, joints: FloatArray) -> FloatArray:
    """Joint torques (N m) that hold each posture still against gravity, both soles loaded.

    Args:
        scene: Scene (its model has the URDF's masses and inertias).
        joints: (n, nj) joint angles, rad.

    Returns:
        (n, nj) torques in the scene's joint order, N m (positive about each joint's axis).

    Example:
        >>> tau = gravity_torques(scene, scene.reference[None, :])  # (1, nj) N m

    """
    joints = np.atleast_2d(joints)
    return holding_torques(scene, joints, [None] * len(joints), 0.0)


def holding_torques(
    scene: Scene, joints: FloatArray, contacts: Sequence[str | None], force_n: float | FloatArray
) -> FloatArray:
    """Joint torques (N m) that hold each posture still under gravity and its hand's contact force.

    Args:
        scene: Scene.
        joints: (n, nj) joint angles, rad.
        contacts: Per posture, the chain whose hand presses on the table, or None (no contact).
        force_n: The table's normal reaction on that hand, N: one value or (n,).

    Returns:
        (n, nj) torques in the scene's joint order, N m.

    Example:
        >>> tau = holding_torques(scene, pool_joints, ["left"] * len(pool_joints), 30.0)

    """
    joints = np.atleast_2d(joints)
    forces = np.broadcast_to(np.asarray(force_n, dtype=float), (len(joints),))
    statics = Statics(scene)
    out = np.zeros((joints.shape[0], len(scene.joint_names)))
    for i, posture in enumerate(joints):
        out[i] = statics.torques(posture, contacts[i], float(forces[i]))
    return out


def linear_torques(scene: Scene, joints: FloatArray, chain: str | None, force_n: float) -> LinearTorques:
    """Holding torques (:func:`holding_torques`) and their first-order change with the joints.

    The floating base follows the joints so that the anchor sole stays on the floor (its
    motion is eliminated through the anchor sole's Jacobian) and the hand's force keeps its
    direction in the world: pinocchio's static torque derivatives, plus the change of the
    weight's split between the feet (the least-size split differentiated), which the leg
    joints carry.

    Args:
        scene: Scene.
        joints: (nj,) rad.
        chain: The chain whose hand presses on the table, or None.
        force_n: The table's normal reaction on that hand, N.

    Example:
        >>> lin = linear_torques(scene, scene.reference, "left", 30.0)
        >>> lin.torques + lin.jacobian @ step  # the torques after a small step (nj,) of the joints

    """
    return Statics(scene).linear(np.asarray(joints, dtype=float), chain, force_n)


def effort_ratios(scene: Scene, torques: FloatArray) -> FloatArray:
    """Each torque as a fraction of its joint's URDF effort limit; nan where the URDF gives none.

    Args:
        scene: Scene.
        torques: (..., nj) N m.

    Returns:
        (..., nj) abs(torque) / effort limit.

    Example:
        >>> ratio = effort_ratios(scene, holding_torques(scene, joints, chains, 30.0))

    """
    return np.abs(np.asarray(torques, dtype=float)) / scene.effort_limit


def worst_effort_ratio(
    scene: Scene, joints: FloatArray, chain: str | None, statics: Statics | None = None
) -> tuple[float, int]:
    """The largest effort ratio of one posture, and its joint (index; -1 when no joint has a limit).

    A posture in contact (``chain`` given) is held both unloaded (at the approach and
    release, the hand above the table) and pressing ``route.contact_force_n``: the worse counts,
    each torque with its spread over the CoM's uncertainty (:meth:`Statics.com_spread`).

    Args:
        scene: Scene.
        joints: (nj,) rad.
        chain: The chain whose hand is on the table, or None.
        statics: A workspace to reuse (one is made if None).

    Example:
        >>> ratio, joint = worst_effort_ratio(scene, posture, "left")

    """
    statics = statics or Statics(scene)
    if chain is None:
        torques, spread = statics.torques(joints, None, 0.0)[None, :], statics.com_spread(joints)
    else:  # both loads and the spread from one kinematics pass (the same numbers)
        pair = statics.torque_pair(joints, chain, scene.route.contact_force_n)
        torques, spread = np.array([pair.unloaded, pair.pressing]), pair.spread
    bound = np.abs(torques) + spread  # (loads, nj) N m
    ratio = np.nan_to_num(effort_ratios(scene, bound), nan=-1.0).max(axis=0)  # (nj,)
    if not np.any(ratio >= 0.0):
        return 0.0, -1
    j = int(np.argmax(ratio))
    return float(ratio[j]), j
