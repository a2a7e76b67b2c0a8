"""Collision pairs kept apart, linearised: rows ``A q <= b`` on the joints of a standing robot.

A projection onto balanced contact knows nothing of collisions; on TALOS 95 % of the
converged samples that then collide are the two thighs, which a projection that keeps
them apart would have saved (the pool's samples were half wasted there). A pair at
distance ``d`` with nearest points ``p1``, ``p2`` and unit normal ``n`` (from the first
body toward the second) moves apart at ``n . (v2(p2) - v1(p1))``: its distance changes by
``g dq`` for a joint step ``dq``, the floating base following so that the anchor sole
stays on the floor (as :mod:`posegen.robot.statics` has it). Kept at ``keep_m`` or more:
``d + g (q' - q) >= keep_m``, i.e. ``-g q' <= d - keep_m - g q``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.robot.collision import CollisionChecker, Witness
from posegen.robot.geometry import FloatArray
from posegen.robot.scene import Scene


@dataclass(frozen=True)
class SeparationRows:
    """Linearised distances of some collision pairs at one posture."""

    pairs: tuple[int, ...]  # (m,) the collision pairs (indices in the checker's geometry)
    distances_m: FloatArray  # (m,) m, each pair's distance now (negative: penetrating)
    gradient: FloatArray  # (m, nj) m/rad, d distance / d joints (the anchor sole fixed)
    joints: FloatArray  # (nj,) rad, the posture they were taken at

    def within(self, distance_m: float) -> SeparationRows:
        """The rows of the pairs closer than ``distance_m``."""
        keep = self.distances_m < distance_m
        pairs = tuple(p for p, k in zip(self.pairs, keep, strict=True) if k)
        return SeparationRows(pairs, self.distances_m[keep], self.gradient[keep], self.joints.copy())

    def half_spaces(self, keep_m: float) -> tuple[FloatArray, FloatArray]:
        """``(A, b)``, (m, nj) and (m,): ``A q <= b`` keeps every pair at ``keep_m`` or more, to first order."""
        return -self.gradient, self.distances_m - keep_m - self.gradient @ self.joints


class Separation:
    """The distance of a robot's collision pairs and its derivative with the joints, both soles down.

    Example:
        >>> separation = Separation(scene, CollisionChecker(scene))
        >>> rows = separation.rows(joints, "left", 0.01)  # the pairs within 1 cm
        >>> a, b = rows.half_spaces(0.008)  # the rows that keep them 8 mm apart

    """

    def __init__(self, scene: Scene, checker: CollisionChecker) -> None:
        self.scene = scene
        self.checker = checker
        self.model = scene.model
        self.data = scene.model.createData()
        self.anchor = scene.frame_id(scene.anchor_sole)
        self.velocity = scene.velocity_indices()  # (nj,) the joints' velocity indices

    def rows(
        self, joints: FloatArray, chain: str | None, within_m: float, pairs: tuple[int, ...] | None = None
    ) -> SeparationRows:
        """The pairs closer than ``within_m`` at ``joints`` (rad, (nj,)), linearised; ``chain``: the one in contact.

        ``pairs``: look at these only (e.g. the ``pairs`` of an earlier call with a larger
        ``within_m``, while the posture moves less than the difference); None: at every pair.

        Example:
            >>> separation.rows(joints, "left", 0.01).distances_m  # (m,) m

        """
        joints = np.array(joints, dtype=float)
        q = self.scene.configuration(joints)
        found = self.checker.witnesses(q, chain, within_m, pairs)
        if not found:
            return SeparationRows((), np.zeros(0), np.zeros((0, len(joints))), joints)
        model, data = self.model, self.data
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        anchor = pin.getFrameJacobian(model, data, self.anchor, pin.LOCAL)  # (6, nv)
        base = -np.linalg.solve(anchor[:, :6], anchor[:, 6:])  # (6, nv - 6) base velocity per joint velocity
        gradient = np.array([self._gradient(w, base) for w in found])  # (m, nj)
        return SeparationRows(tuple(w.pair for w in found), np.array([w.distance_m for w in found]), gradient, joints)

    def _gradient(self, witness: Witness, base: FloatArray) -> FloatArray:
        """(nj,) m/rad the pair's distance change per joint, the base following the anchor sole."""
        (first, second), (joint_1, joint_2) = witness.points_m, witness.joints
        velocity = self._point_jacobian(joint_2, second) - self._point_jacobian(joint_1, first)  # (3, nv)
        change = witness.normal @ velocity  # (nv,)
        return np.asarray((change[6:] + change[:6] @ base)[self.velocity - 6])

    def _point_jacobian(self, joint: int, point_m: FloatArray) -> FloatArray:
        """(3, nv) world velocity of the body point at ``point_m`` (world) carried by ``joint`` (0: fixed)."""
        if joint == 0:
            return np.zeros((3, self.model.nv))
        jacobian = pin.getJointJacobian(self.model, self.data, joint, pin.LOCAL_WORLD_ALIGNED)  # (6, nv)
        lever = point_m - self.data.oMi[joint].translation
        return np.asarray(jacobian[:3] - pin.skew(lever) @ jacobian[3:])
