"""Checks of a scene that a config can get wrong although every name in it exists.

Each failure is a one-line :class:`~posegen.errors.ConfigError` naming the config field
to change: a reference posture whose soles are not on one floor, that is not balanced
or that is in collision; a sole frame that is not under the robot; a table that no
chain can reach. They guard planning (``pool``, ``route``), not every use of a scene: a
calibrated robot, say, no longer closes its nominal reference posture exactly, and its
scene must still load to evaluate its contacts.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError
from posegen.robot.geometry import tilt_angles

if TYPE_CHECKING:  # the scene runs the kinematic checks when it is built
    from posegen.robot.collision import CollisionChecker
    from posegen.robot.scene import Scene

SOLE_HEIGHT_TOL_M = 0.005  # second sole above or below the first's floor
SOLE_TILT_TOL_RAD = float(np.deg2rad(1.0))  # second sole tilted with respect to the first
BELOW_SOLE_TOL_M = 0.01  # a joint this far below the soles' floor: they are not under the robot


def check_for_planning(scene: Scene, checker: CollisionChecker | None = None) -> None:
    """Every check of this module; the collision check only with a ``checker``.

    Raises:
        ConfigError: The first failing check, naming its config field.

    """
    check_stance(scene)
    check_reference_limits(scene)
    check_reach(scene)
    if checker is not None:
        check_reference_collisions(scene, checker)


def check_stance(scene: Scene) -> None:
    """The reference posture stands on both soles, flat on one floor, and is balanced.

    Raises:
        ConfigError: Naming ``stance.sole_frames`` or ``stance.reference_posture``.

    """
    name = _reference_name(scene)
    q = scene.configuration(scene.reference)
    data = scene.model.createData()
    pin.framesForwardKinematics(scene.model, data, q)
    anchor, second = scene.anchor_sole, scene.second_sole
    relative = data.oMf[scene.frame_id(anchor)].actInv(data.oMf[scene.frame_id(second)])
    roll, pitch = tilt_angles(relative.rotation)
    height = float(relative.translation[2])
    if abs(height) > SOLE_HEIGHT_TOL_M or max(abs(roll), abs(pitch)) > SOLE_TILT_TOL_RAD:
        raise ConfigError(
            f"stance.reference_posture: at {name} the soles are not on one floor: '{second}' is "
            f"{1e3 * height:+.1f} mm above '{anchor}' and tilted by roll {np.rad2deg(roll):.1f} deg, "
            f"pitch {np.rad2deg(pitch):.1f} deg"
        )
    floor = data.oMf[scene.frame_id(anchor)]
    depths = [float(floor.actInv(data.oMi[j]).translation[2]) for j in range(2, scene.model.njoints)]
    lowest = int(np.argmin(depths))
    if depths[lowest] < -BELOW_SOLE_TOL_M:
        raise ConfigError(
            f"stance.sole_frames: '{anchor}' is not under the robot: joint '{scene.model.names[lowest + 2]}' "
            f"is {-1e3 * depths[lowest]:.0f} mm below it"
        )
    margin = scene.com_margin(q, data)
    if margin < scene.margins.com_m:
        raise ConfigError(
            f"stance.reference_posture: {name} is not balanced: its CoM is {1e3 * margin:.1f} mm inside the "
            f"support polygon, the margin needs {1e3 * scene.margins.com_m:.1f} mm (set stance.reference_joints)"
        )


def check_reference_limits(scene: Scene) -> None:
    """The reference posture keeps every free joint the configured margin inside its limits.

    Raises:
        ConfigError: Naming ``stance.reference_joints`` and the joint closest to a limit.

    """
    gap = np.minimum(scene.reference - scene.lower, scene.upper - scene.reference)  # (nj,) rad
    slack = gap - scene.limit_margins  # (nj,) rad
    slack[scene.locked] = np.inf
    worst = int(np.argmin(slack))
    if slack[worst] < 0.0:
        raise ConfigError(
            f"stance.reference_joints: at {_reference_name(scene)} joint '{scene.joint_names[worst]}' is "
            f"{gap[worst]:.3f} rad from a limit [{scene.lower[worst]:.3f}, {scene.upper[worst]:.3f}], the margin "
            f"needs {scene.limit_margins[worst]:g} rad (margins.joint_limit_rad{_own(scene, worst)}): move it inside"
        )


def check_reach(scene: Scene) -> None:
    """Every chain can reach the table spots it serves, by an upper bound on its length.

    A chain reaches at most the sum of the lengths between consecutive joints (triangle
    inequality): from its sole up the leg to the root, then down to the contact. A spot
    farther than that from the sole is out of reach whatever the posture.

    Raises:
        ConfigError: Naming ``table.top_center_m``.

    """
    model = scene.model
    data = model.createData()
    q = scene.configuration(scene.reference)
    pin.framesForwardKinematics(model, data, q)
    for chain in scene.chains:
        reach = _length_to_root(model, chain.sole_frame) + _length_to_root(model, chain.frame(chain.contact_kind))
        sole = data.oMf[scene.frame_id(chain.sole_frame)].translation
        spots = [s for s in scene.spots if chain.name in s.chains]
        if not spots:
            continue
        distances = [float(np.linalg.norm(scene.spot_world(s) - sole)) for s in spots]
        if min(distances) > reach:
            raise ConfigError(
                f"table.top_center_m: out of reach of chain '{chain.name}': its nearest spot is "
                f"{min(distances):.2f} m from '{chain.sole_frame}', the chain is {reach:.2f} m long"
            )


def check_reference_collisions(scene: Scene, checker: CollisionChecker) -> None:
    """The reference posture, with the locked joints at their values, is collision-free.

    Raises:
        ConfigError: Naming ``stance.reference_posture`` and the closest pair.

    """
    joints = np.where(scene.locked, scene.locked_values, scene.reference)
    hits = checker.colliding_pairs(scene.configuration(joints), None, scene.margins.collision_m)
    if hits:
        worst = hits[0]
        raise ConfigError(
            f"stance.reference_posture: {_reference_name(scene)} is in collision: {worst.pair[0]} - "
            f"{worst.pair[1]} at {1e3 * worst.distance_m:.1f} mm (margin {1e3 * scene.margins.collision_m:.0f} mm; "
            f"{len(hits)} pair(s)); change stance.reference_joints or disable pairs that touch at rest "
            "(posegen robot init)"
        )


def _own(scene: Scene, joint: int) -> str:
    """The config key of a joint's own margin, if it has one."""
    name = scene.joint_names[joint]
    return f"_by_joint.{name}" if name in scene.margins.joint_limit_rad_by_joint else ""


def _reference_name(scene: Scene) -> str:
    name = scene.stance.reference_posture or "the zero posture"
    return f"'{name}'" + (" with stance.reference_joints" if scene.stance.reference_joints else "")


def _length_to_root(model: pin.Model, frame_name: str) -> float:
    """Sum of the distances between consecutive joints from a frame up to the root (m)."""
    frame = model.frames[model.getFrameId(frame_name)]
    total = float(np.linalg.norm(frame.placement.translation))
    joint = frame.parentJoint
    while joint > 1:
        total += float(np.linalg.norm(model.jointPlacements[joint].translation))
        joint = model.parents[joint]
    return total
