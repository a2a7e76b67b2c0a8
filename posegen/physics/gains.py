"""Joint position loop gains and rotor inertias, from the URDF alone.

A humanoid's joint drives are stiff position loops whose torque is capped by the motor's
current limit (the URDF's ``effort``). The loop is sized from that limit: it reaches its
cap at ``SATURATION_RAD`` of error, ``kp = effort / SATURATION_RAD``, and is critically
damped on the inertia the joint moves at the reference posture, standing: every other
joint still and a sole on the floor (for a leg's joint, its own sole: the ankle moves the
whole robot, not its foot), plus the rotor's. Damped on the foot alone, a stiff ankle
loop would let the standing robot rock at about 2 Hz. The rotor inertia reflected through the gear
(``armature``) grows with the drive's size: ``ARMATURE_PER_NM`` x effort, as harmonic
drives of 100-160:1 give. A joint without an effort limit gets the gains of
``DEFAULT_EFFORT_NM``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.robot import FloatArray, Scene

SATURATION_RAD = 0.01  # position error at which a joint loop reaches its effort limit
ARMATURE_PER_NM = 1e-3  # kg m^2 of reflected rotor inertia per N m of effort
MIN_ARMATURE = 5e-3  # kg m^2
DEFAULT_EFFORT_NM = 50.0  # sizes the loop of a joint the URDF gives no effort limit
DAMPING_RATIO = 1.0


@dataclass(frozen=True)
class Gains:
    """Each actuated joint's loop (scene joint order)."""

    kp: FloatArray  # (nj,) N m / rad
    kd: FloatArray  # (nj,) N m s / rad
    armature: FloatArray  # (nj,) kg m^2


def joint_gains(scene: Scene) -> Gains:
    """The joint loops of the scene's robot, sized from its URDF's efforts and inertias.

    Example:
        >>> gains = joint_gains(scene)
        >>> gains.kp[scene.joint_index("leg_left_4_joint")]  # 300 N m / 0.01 rad
        30000.0

    """
    model = scene.model
    velocity = scene.velocity_indices()
    effort = np.array(model.effortLimit[velocity], dtype=float)
    effort = np.where(np.isfinite(effort) & (effort > 0), effort, DEFAULT_EFFORT_NM)
    armature = np.maximum(ARMATURE_PER_NM * effort, MIN_ARMATURE)
    inertia = standing_inertia(scene)[velocity] + armature
    kp = effort / SATURATION_RAD
    kd = 2.0 * DAMPING_RATIO * np.sqrt(kp * inertia)
    return Gains(kp, kd, armature)


def standing_inertia(scene: Scene) -> FloatArray:
    """(nv,) kg m^2: the inertia each joint moves at the reference posture, the others still, a sole fixed.

    Moving joint ``i`` alone with sole ``s`` on the floor moves the base by
    ``-J_s,base^-1 J_s,i``; the inertia is ``u^T M u`` for that motion ``u``, the largest
    over the soles. (Free-flyer entries are returned but not used.)
    """
    model, data = scene.model, scene.model.createData()
    q = scene.configuration(scene.reference)
    mass = pin.crba(model, data, q)
    mass = np.triu(mass) + np.triu(mass, 1).T  # crba fills the upper triangle
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    inertia = np.diag(mass).copy()
    for sole in scene.stance.sole_frames:
        jacobian = pin.getFrameJacobian(model, data, scene.frame_id(sole), pin.LOCAL)  # (6, nv)
        motions = np.vstack([-np.linalg.solve(jacobian[:, :6], jacobian[:, 6:]), np.eye(model.nv - 6)])  # (nv, nv-6)
        standing = np.einsum("ij,ik,kj->j", motions, mass, motions)  # u_j^T M u_j per joint
        inertia[6:] = np.maximum(inertia[6:], standing)
    return inertia
