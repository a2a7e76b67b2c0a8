"""What calibration needs of a scene's chain frames, checked before any work.

The calibration identifies, per chain, the placements from the sole frame to the
gripper frame and the contact's offsets in the gripper frame, then writes them back
into the robot's URDF. That is only sound when:

* the sole and gripper frames are fixed placements: a link of the URDF attached by a
  fixed joint, or a frame the config declares (``robot.frames``); a link that a moving
  joint carries is that joint's own frame, and writing a placement into it would
  overwrite the joint's origin;
* each sole frame is level at the reference posture (the table plane is a small tilt
  in the sole frame);
* the contact points (fingertip frames, point frame) ride on the gripper frame: every
  joint between them is locked (``robot.locked_joints``), or the contact moves in a way
  the model does not know.

:func:`check_calibration_frames` says the first breach in one line naming the config
field; :func:`declared_chain_frames` lists the chain frames the URDF file lacks (those
an exported URDF must add).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError
from posegen.robot.scene import Scene

LEVEL_TOL_RAD = float(np.deg2rad(1.0))


def check_calibration_frames(scene: Scene) -> None:
    """Check that every chain's frames can be calibrated and written back.

    Raises:
        ConfigError: The first frame that cannot, naming its config field.

    """
    fixed_children = _fixed_children(scene.files.urdf_text())
    declared = {frame.name for frame in scene.config.frames}
    data = scene.model.createData()
    pin.framesForwardKinematics(scene.model, data, scene.configuration(scene.reference))
    for chain in scene.chains:
        for field, name in (("sole_frame", chain.sole_frame), ("gripper_frame", chain.gripper_frame)):
            if name not in declared and name not in fixed_children:
                raise ConfigError(
                    f"chains.{chain.name}.{field}: '{name}' is moved by joint "
                    f"'{scene.model.names[scene.model.frames[scene.frame_id(name)].parentJoint]}' itself: calibration "
                    "writes a placement into the joint that carries the frame; use a link fixed to it, or declare a "
                    "frame there (robot.frames)"
                )
        tilt = np.arccos(np.clip(data.oMf[scene.frame_id(chain.sole_frame)].rotation[2, 2], -1.0, 1.0))
        if tilt > LEVEL_TOL_RAD:
            raise ConfigError(
                f"chains.{chain.name}.sole_frame: '{chain.sole_frame}' is tilted {np.rad2deg(tilt):.1f} deg from "
                "level at the reference posture; the table plane is measured in it: use a frame with z up"
            )
        contacts = (*chain.fingertip_frames, *((chain.point_frame,) if chain.point_frame else ()))
        for name in contacts:
            moving = _free_joints_between(scene, chain.gripper_frame, name)
            if moving:
                raise ConfigError(
                    f"chains.{chain.name}: contact frame '{name}' moves on joint(s) {', '.join(moving)} relative to "
                    f"the gripper frame '{chain.gripper_frame}': lock them (robot.locked_joints)"
                )


def declared_chain_frames(scene: Scene) -> tuple[str, ...]:
    """The chains' sole and gripper frames that the config declares (absent from the URDF file)."""
    declared = {frame.name for frame in scene.config.frames}
    names = [name for chain in scene.chains for name in (chain.sole_frame, chain.gripper_frame) if name in declared]
    return tuple(dict.fromkeys(names))


def _fixed_children(urdf_text: str) -> set[str]:
    """Links that are the child of a fixed joint in a URDF."""
    root = ET.fromstring(urdf_text)
    out = set()
    for joint in root.findall("joint"):
        child = joint.find("child")
        if joint.get("type") == "fixed" and child is not None:
            out.add(str(child.get("link")))
    return out


def _free_joints_between(scene: Scene, gripper: str, frame: str) -> list[str]:
    """Joints on the path from the gripper frame to a contact frame that are neither fixed nor locked."""
    model = scene.model
    start = model.frames[scene.frame_id(gripper)].parentJoint
    joint = model.frames[scene.frame_id(frame)].parentJoint
    path = []
    while joint not in (start, 0):
        path.append(joint)
        joint = model.parents[joint]
    if joint != start:
        return []  # not below the gripper: the scene's contact placement says where it is
    locked = set(scene.config.locked_joints)
    return [str(model.names[j]) for j in reversed(path) if str(model.names[j]) not in locked]
