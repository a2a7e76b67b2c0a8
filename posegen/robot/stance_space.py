"""The configuration space of a robot standing on both feet, parametrised explicitly.

Planning in the full joint space with both soles fixed is planning on a closed-chain
manifold. Here the second leg is not a planning coordinate: a state is every other free
joint (anchor leg, torso, arms), and the second leg is solved from it (Gauss-Newton
from the previous state's leg, a few milliseconds) so that its sole meets its fixed
pose. Both soles are therefore exact at every state, and an ordinary sampling planner
(OMPL) works in the remaining coordinates.
"""

from __future__ import annotations

import numpy as np

from posegen.robot.collision import CollisionChecker
from posegen.robot.geometry import FloatArray
from posegen.robot.scene import Scene
from posegen.robot.statics import Statics


class StanceSpace:
    """Explicit coordinates of the standing robot and the validity of its states.

    Attributes:
        coordinates: Indices (in Scene.joint_names) of the planning coordinates.
        closing: Indices of the second leg's joints, solved from the others.
        lower, upper: Bounds of the coordinates (joint limits shrunk by the margin), rad.

    """

    def __init__(self, scene: Scene, checker: CollisionChecker) -> None:
        self.scene = scene
        self.checker = checker
        self.closing = scene.leg_joints(scene.second_sole)
        self.coordinates = [
            i for i in range(len(scene.joint_names)) if not scene.locked[i] and i not in set(self.closing)
        ]
        lower, upper = scene.planning_limits()  # (nj,) rad
        self.lower = lower[self.coordinates]
        self.upper = upper[self.coordinates]
        self._data = scene.model.createData()
        self._statics = Statics(scene)
        self._allowed = scene.margins.effort_ratio * scene.effort_limit  # (nj,) N m; nan: no limit
        self._limited = np.isfinite(self._allowed)

    def coordinates_of(self, joints: FloatArray) -> FloatArray:
        """Planning coordinates of full joint angles. Shape (nc,)."""
        return np.array(joints[self.coordinates], dtype=float)

    def joints_of(self, x: FloatArray, warm: FloatArray) -> FloatArray | None:
        """Full joint angles of coordinates ``x``, the second leg closed from ``warm``.

        Returns:
            (nj,) joint angles, or None if the second sole cannot be reached.

        """
        joints = np.array(warm, dtype=float)
        joints[self.coordinates] = x
        return self.scene.close_stance(joints)

    def holds(self, joints: FloatArray, pressing: str | None) -> bool:
        """Whether every holding torque, with its spread over the CoM's uncertainty, is within the effort margin.

        Args:
            joints: (nj,) rad.
            pressing: The chain whose hand presses the table with ``route.contact_force_n``, or None.

        """
        if not np.any(self._limited):
            return True
        torques = self._statics.torques(joints, pressing, self.scene.route.contact_force_n)
        bound = np.abs(torques) + self._statics.com_spread(joints)  # (nj,) N m
        return bool(np.all(bound[self._limited] <= self._allowed[self._limited]))

    def is_valid(
        self,
        joints: FloatArray,
        contact_chain: str | None,
        collision_margin_m: float | None = None,
        near_table: bool = False,
    ) -> bool:
        """Limits (with margin), CoM inside the polygon with margin, torques, no collision with margin.

        The holding torques are those of the hand unloaded (a state the planner moves
        through; a contact's go-to-contact is checked pressing, :meth:`holds_pressing`).
        A free state (no ``contact_chain``, not ``near_table``) keeps every body
        ``margins.table_clearance_m`` above the table: the true hand may be lower than the model's.

        Args:
            joints: (nj,) joint angles with both soles closed.
            contact_chain: Chain whose fingertips may touch the table, or None.
            collision_margin_m: Collision margin; None: the configured one.
            near_table: A state of a vertical approach, which ends just above the table: the
                collision margin only.

        Example:
            >>> space.is_valid(stop.approach[-1], None, near_table=True)  # 1 cm above the table
            True

        """
        scene = self.scene
        margins = scene.margins
        if scene.limit_margin(joints) < margins.joint_limit_rad - 1e-9:
            return False
        q = scene.configuration(joints)
        if scene.com_margin(q, self._data) < margins.com_m:
            return False
        if not self.holds(joints, None):
            return False
        margin = margins.collision_m if collision_margin_m is None else collision_margin_m
        free = contact_chain is None and not near_table and margins.table_clearance_m > 0
        return not self.checker.collides(q, contact_chain, margin, margins.table_clearance_m if free else None)
