"""Feasibility of a contact posture, measured with pinocchio and coal only.

Nothing here trusts the solver that produced a posture: the floating base is re-solved
from the anchor sole, and every invariant is measured from forward kinematics.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.robot.balance import pressed_zmp_margin
from posegen.robot.collision import CollisionChecker, Proximity
from posegen.robot.contact_kinds import DEFAULT_KIND, ContactKind
from posegen.robot.geometry import FloatArray, tilt_angles
from posegen.robot.scene import Scene
from posegen.robot.statics import Statics, worst_effort_ratio

SOLE_POSITION_TOL_M = 1e-4
SOLE_ANGLE_TOL_RAD = 1e-3
CONTACT_HEIGHT_TOL_M = 1e-4
CONTACT_ANGLE_TOL_RAD = 1e-3
JOINT_LIMIT_TOL_RAD = 1e-9
EFFORT_RATIO_TOL = 1e-6  # on the effort ratio: float32 storage of the angles moves a torque by ~1e-5 N m


class Invariant(str, enum.Enum):
    """What a contact posture must satisfy."""

    SOLE = "sole"  # the non-anchor sole at its fixed pose
    CONTACT = "contact"  # flush: contact frame on the table plane; point: tip on it, tilt within the cone
    COM = "com"  # CoM projection inside the support polygon with margin
    JOINT_LIMITS = "joint_limits"  # within the limits shrunk by the margin
    COLLISION = "collision"  # no pair closer than the collision margin
    ZMP = "zmp"  # the soles' centre of pressure with the hand pressing the contact force, inside by margins.zmp_m
    TORQUE = "torque"  # holding torques (hand unloaded and pressing) within the effort limits times the margin


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
    contact_kind: ContactKind = DEFAULT_KIND
    contact_tilt_rad: float = 0.0  # angle between the contact frame's z and the table normal
    cone_rad: float = 0.0  # a point contact's largest tilt (not used by a flush one)
    pressed_zmp_margin_m: float = np.inf  # signed: the centre of pressure, the hand pressing, inside the polygon
    effort_ratio: float = 0.0  # largest holding torque / URDF effort limit (0: no joint has a limit)
    effort_joint: str = ""  # the joint of that ratio

    def excess(self, scene: Scene) -> dict[Invariant, float]:
        """Each measured invariant's excess over its bound (> 0: violated), in its unit."""
        margins = scene.margins
        torque = self.effort_ratio - margins.effort_ratio - EFFORT_RATIO_TOL if self.effort_joint else -1.0
        found = {
            Invariant.SOLE: max(
                self.sole_position_error_m - SOLE_POSITION_TOL_M,
                self.sole_angle_error_rad - SOLE_ANGLE_TOL_RAD,
            ),
            Invariant.CONTACT: self._contact_excess(),
            Invariant.COM: margins.com_m - self.com_margin_m,
            Invariant.JOINT_LIMITS: margins.joint_limit_rad - self.joint_limit_margin_rad - JOINT_LIMIT_TOL_RAD,
            Invariant.ZMP: margins.zmp_m - self.pressed_zmp_margin_m,
            Invariant.TORQUE: torque,
        }
        if self.closest is not None:
            found[Invariant.COLLISION] = margins.collision_m - self.closest.distance_m
        return found

    def contact_detail(self) -> str:
        """The contact's measured figures, as a short text."""
        return self.contact_kind.detail(self)

    def _contact_excess(self) -> float:
        return self.contact_kind.excess(self, CONTACT_HEIGHT_TOL_M, CONTACT_ANGLE_TOL_RAD)

    def violations(self, scene: Scene) -> dict[Invariant, float]:
        """The violated invariants with their excess over the bound."""
        return {k: v for k, v in self.excess(scene).items() if v > 0}


def contact_in_table(scene: Scene, data: pin.Data, chain: str) -> pin.SE3:
    """Pose of a chain's planned contact frame in the table frame (after forward kinematics).

    For a point contact, the frame at the tip's centre, its radius above the table.
    """
    config = scene.chain(chain)
    frame = scene.frame_id(config.frame(config.contact_kind))
    return pin.SE3(scene.table_pose).actInv(data.oMf[frame])


def assess(
    scene: Scene,
    checker: CollisionChecker | None,
    joints: FloatArray,
    chain: str,
    statics: Statics | None = None,
    data: pin.Data | None = None,
) -> Assessment:
    """Measure every invariant of a posture whose ``chain`` touches the table.

    Args:
        scene: The scene.
        checker: Collision checker measuring the closest pair; None to skip collisions.
        joints: Actuated joint angles (rad), shape (nj,).
        chain: Name of the chain in contact.
        statics: A statics workspace to reuse for the holding torques (one is made if None).
        data: A pinocchio workspace of ``scene.model`` to reuse (one is made if None: it costs
            a millisecond, several times the assessment).

    """
    q = scene.configuration(joints)
    model = scene.model
    data = model.createData() if data is None else data
    pin.framesForwardKinematics(model, data, q)
    other = scene.second_sole
    sole_error = pin.SE3(scene.sole_poses[other]).actInv(data.oMf[scene.frame_id(other)])
    contact = contact_in_table(scene, data, chain)
    config = scene.chain(chain)
    lift = config.contact_kind.lift_m(config)
    roll, pitch = tilt_angles(contact.rotation)
    limit_margin = float(scene.limit_margin(joints))  # locked joints may sit on a limit: not counted
    closest = checker.closest(q, chain) if checker is not None else None
    ratio, joint = worst_effort_ratio(scene, joints, chain, statics)
    com_margin = scene.com_margin(q, data)  # data.com[0], data.mass[0] hold the CoM and the mass
    hand = data.oMf[scene.frame_id(config.frame(config.contact_kind))].translation
    pressed = pressed_zmp_margin(scene, data.com[0], float(data.mass[0]), hand, scene.route.contact_force_n)
    return Assessment(
        sole_position_error_m=float(np.linalg.norm(sole_error.translation)),
        sole_angle_error_rad=float(np.linalg.norm(pin.log3(sole_error.rotation))),
        contact_height_m=float(contact.translation[2]) - lift,
        contact_roll_rad=roll,
        contact_pitch_rad=pitch,
        contact_xy_table_m=(float(contact.translation[0]), float(contact.translation[1])),
        contact_yaw_rad=float(np.arctan2(contact.rotation[1, 0], contact.rotation[0, 0])),
        com_margin_m=com_margin,
        joint_limit_margin_rad=limit_margin,
        closest=closest,
        contact_kind=config.contact_kind,
        contact_tilt_rad=float(np.arccos(np.clip(contact.rotation[2, 2], -1.0, 1.0))),
        cone_rad=float(np.deg2rad(config.point_cone_deg)),
        pressed_zmp_margin_m=pressed,
        effort_ratio=ratio,
        effort_joint=scene.joint_names[joint] if joint >= 0 else "",
    )
