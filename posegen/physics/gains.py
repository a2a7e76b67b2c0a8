"""Joint position loop gains and rotor inertias, from the URDF alone.

A humanoid's joint drives are stiff position loops whose torque is capped by the motor's
current limit (the URDF's ``effort``). The loop is sized from that limit: it reaches its
cap at ``SATURATION_RAD`` of error, ``kp = effort / SATURATION_RAD``, and is critically
damped on the joint's inertia at the reference posture (its link subtree, from the
nominal mass matrix, plus the rotor's). The rotor inertia reflected through the gear
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
        >>> gains.kp[scene.joint_index("leg_left_4_joint")]  # 300 N m / 0.05 rad
        6000.0

    """
    model = scene.model
    velocity = scene.velocity_indices()
    effort = np.array(model.effortLimit[velocity], dtype=float)
    effort = np.where(np.isfinite(effort) & (effort > 0), effort, DEFAULT_EFFORT_NM)
    armature = np.maximum(ARMATURE_PER_NM * effort, MIN_ARMATURE)
    mass = pin.crba(model, model.createData(), scene.configuration(scene.reference))
    inertia = np.diag(mass)[velocity] + armature
    kp = effort / SATURATION_RAD
    kd = 2.0 * DAMPING_RATIO * np.sqrt(kp * inertia)
    return Gains(kp, kd, armature)
