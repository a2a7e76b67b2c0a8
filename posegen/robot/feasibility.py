"""Feasibility of a contact posture, measured with pinocchio and coal only.

Nothing here trusts the solver that produced a posture: the floating base is re-solved
from the anchor sole, and every invariant is measured from forward kinematics.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.robot.collision import CollisionChecker, Proximity
from posegen.robot.geometry import FloatArray, tilt_angles
from posegen.robot.scene import Scene

SOLE_POSITION_TOL_M = 1e-4
SOLE_ANGLE_TOL_RAD = 1e-3
CONTACT_HEIGHT_TOL_M = 1e-4
CONTACT_ANGLE_TOL_RAD = 1e-3
JOINT_LIMIT_TOL_RAD = 1e-9


class Invariant(str, enum.Enum):
    """What a contact posture must satisfy."""

    SOLE = "sole"  # the non-anchor sole at its fixed pose
    CONTACT = "contact"  # contact frame flush on the table plane
    COM = "com"  # CoM projection inside the support polygon with margin
    JOINT_LIMITS = "joint_limits"  # within the limits shrunk by the margin
    COLLISION = "collision"  # no pair closer than the collision margin


@dataclass(frozen=True)
class Assessment:
    """Measured invariants of one posture in contact."""

    sole_position_error_m: float
    sole_angle_error_rad: float
    contact_height_m: float  # contact frame origin above the table plane
    contact_roll_rad: float
    contact_pitch_rad: float
    contact_xy_table_m: tuple[float, float]
    contact_yaw_rad: float
    com_margin_m: float  # signed: negative outside the polygon
    joint_limit_margin_rad: float  # smallest distance of a free joint to a limit (negative outside)
    closest: Proximity | None  # None: collisions not measured here

    def excess(self, scene: Scene) -> dict[Invariant, float]:
        """Each measured invariant's excess over its bound (> 0: violated), in its unit."""
        margins = scene.margins
        found = {
            Invariant.SOLE: max(
                self.sole_position_error_m - SOLE_POSITION_TOL_M,
                self.sole_angle_error_rad - SOLE_ANGLE_TOL_RAD,
            ),
            Invariant.CONTACT: max(
                abs(self.contact_height_m) - CONTACT_HEIGHT_TOL_M,
                abs(self.contact_roll_rad) - CONTACT_ANGLE_TOL_RAD,
                abs(self.contact_pitch_rad) - CONTACT_ANGLE_TOL_RAD,
            ),
            Invariant.COM: margins.com_m - self.com_margin_m,
            Invariant.JOINT_LIMITS: margins.joint_limit_rad - self.joint_limit_margin_rad - JOINT_LIMIT_TOL_RAD,
        }
        if self.closest is not None:
            found[Invariant.COLLISION] = margins.collision_m - self.closest.distance_m
        return found

    def violations(self, scene: Scene) -> dict[Invariant, float]:
        """The violated invariants with their excess over the bound."""
        return {k: v for k, v in self.excess(scene).items() if v > 0}


def contact_in_table(scene: Scene, data: pin.Data, chain: str) -> pin.SE3:
    """Pose of a chain's contact frame in the table frame (after forward kinematics)."""
    frame = scene.frame_id(scene.chain(chain).contact_frame)
    return pin.SE3(scene.table_pose).actInv(data.oMf[frame])


def assess(scene: Scene, checker: CollisionChecker | None, joints: FloatArray, chain: str) -> Assessment:
    """Measure every invariant of a posture whose ``chain`` touches the table.

    Args:
        scene: The scene.
        checker: Collision checker measuring the closest pair; None to skip collisions.
        joints: Actuated joint angles (rad), shape (nj,).
        chain: Name of the chain in contact.

    """
    q = scene.configuration(joints)
    model = scene.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    other = scene.second_sole
    sole_error = pin.SE3(scene.sole_poses[other]).actInv(data.oMf[scene.frame_id(other)])
    contact = contact_in_table(scene, data, chain)
    roll, pitch = tilt_angles(contact.rotation)
    limit_margin = float(scene.limit_margin(joints))  # locked joints may sit on a limit: not counted
    closest = checker.closest(q, chain) if checker is not None else None
    return Assessment(
        sole_position_error_m=float(np.linalg.norm(sole_error.translation)),
        sole_angle_error_rad=float(np.linalg.norm(pin.log3(sole_error.rotation))),
        contact_height_m=float(contact.translation[2]),
        contact_roll_rad=roll,
        contact_pitch_rad=pitch,
        contact_xy_table_m=(float(contact.translation[0]), float(contact.translation[1])),
        contact_yaw_rad=float(np.arctan2(contact.rotation[1, 0], contact.rotation[0, 0])),
        com_margin_m=scene.com_margin(q, data),
        joint_limit_margin_rad=limit_margin,
        closest=closest,
    )
