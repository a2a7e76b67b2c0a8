"""The tool a wrist force/torque sensor carries: where the sensor sits, the tool's mass and centre of mass.

A sensor measures the wrench between the link it is mounted on and that link's parent:
everything beyond it (the links below it in the URDF tree, fingers included) is its
tool. A chain's wrench frame may be such a link (TALOS's ``wrist_left_ft_link``), or a
frame that nothing hangs from (a frame declared on the hand): the sensor then sits on
the nearest link above it that carries mass below, and reads in the frame's axes at the
frame's origin.

The controllers know the tool from the nominal URDF (its links' inertials, finger
joints at their locked values); a perturbed robot's tool weighs the same.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError
from posegen.robot import FloatArray, Scene


@dataclass(frozen=True)
class Tool:
    """A wrist sensor's mounting and the tool beyond it (nominal URDF)."""

    frame: str  # the frame the sensor reads in
    link: str  # the link the sensor is mounted on (its subtree is the tool)
    frame_in_link: FloatArray  # (4, 4) the reading frame in that link
    mass_kg: float
    com_m: FloatArray  # (3,) the tool's centre of mass in the reading frame


@dataclass(frozen=True)
class _Tree:
    parent: dict[str, tuple[str, str]]  # child link -> (parent link, joint name)
    children: dict[str, list[tuple[str, ET.Element]]]  # link -> (child link, joint element)
    inertial: dict[str, tuple[float, FloatArray]]  # link -> (mass kg, CoM (3,) in the link)


def _origin(element: ET.Element | None) -> FloatArray:
    """A URDF ``origin`` as a (4, 4) transform (identity when absent)."""
    pose = np.eye(4)
    if element is None:
        return pose
    xyz = [float(v) for v in element.get("xyz", "0 0 0").split()]
    rpy = [float(v) for v in element.get("rpy", "0 0 0").split()]
    pose[:3, :3] = pin.rpy.rpyToMatrix(*rpy)
    pose[:3, 3] = xyz
    return pose


def _axis(joint: ET.Element) -> FloatArray:
    """A URDF joint's axis (3,) in its frame (URDF's default 1 0 0 when absent)."""
    found = joint.find("axis")
    return np.array([float(v) for v in (found.get("xyz", "1 0 0") if found is not None else "1 0 0").split()])


def _tree(urdf_xml: str) -> _Tree:
    root = ET.fromstring(urdf_xml)
    parent: dict[str, tuple[str, str]] = {}
    children: dict[str, list[tuple[str, ET.Element]]] = {}
    for joint in root.findall("joint"):
        up, down = joint.find("parent"), joint.find("child")
        if up is None or down is None:
            continue
        parent[str(down.get("link"))] = (str(up.get("link")), str(joint.get("name")))
        children.setdefault(str(up.get("link")), []).append((str(down.get("link")), joint))
    inertial: dict[str, tuple[float, FloatArray]] = {}
    for link in root.findall("link"):
        found = link.find("inertial")
        mass = None if found is None else found.find("mass")
        if found is not None and mass is not None:
            inertial[str(link.get("name"))] = (float(mass.get("value", "0")), _origin(found.find("origin"))[:3, 3])
    return _Tree(parent, children, inertial)


def _subtree_mass(tree: _Tree, link: str, pose: FloatArray, angles: dict[str, float]) -> tuple[float, FloatArray]:
    """Mass (kg) and first moment (kg m, (3,), in the frame ``pose`` is relative to) of a link's subtree."""
    mass, com = tree.inertial.get(link, (0.0, np.zeros(3)))
    total, moment = mass, mass * (pose[:3, :3] @ com + pose[:3, 3])
    for child, joint in tree.children.get(link, []):
        step = _origin(joint.find("origin"))
        if joint.get("type") in ("revolute", "continuous"):
            axis = _axis(joint)
            turn = np.eye(4)
            turn[:3, :3] = pin.exp3(axis * angles.get(str(joint.get("name")), 0.0))
            step = step @ turn
        elif joint.get("type") == "prismatic":
            axis = _axis(joint)
            step = step @ np.block(
                [[np.eye(3), (axis * angles.get(str(joint.get("name")), 0.0))[:, None]], [0, 0, 0, 1]]
            )
        m, first = _subtree_mass(tree, child, pose @ step, angles)
        total += m
        moment = moment + first
    return total, moment


def wrist_tool(scene: Scene, frame: str) -> Tool:
    """The sensor mounting and tool of a wrench frame, from the scene's URDF.

    Args:
        scene: The nominal scene (its URDF has the config's frames as links).
        frame: The wrench frame (a link, or a frame declared on one).

    Raises:
        ConfigError: Nothing with mass hangs below the frame or any link above it.

    Example:
        >>> wrist_tool(scene, "wrist_left_ft_link").mass_kg  # TALOS's gripper, about 1.4 kg
        1.43...

    """
    tree = _tree(scene.urdf_xml)
    angles = dict(zip(scene.joint_names, scene.locked_values, strict=True))
    link, in_link = frame, np.eye(4)
    mass, moment = _subtree_mass(tree, link, np.eye(4), angles)
    while mass <= 0:  # a frame nothing with mass hangs from: the sensor sits on the link above
        up = tree.parent.get(link)
        joint = None if up is None else next(j for c, j in tree.children[up[0]] if c == link)
        if up is None or joint is None or joint.get("type") != "fixed":
            raise ConfigError(f"no link with mass below the wrench frame '{frame}': no wrist sensor can be placed")
        in_link = _origin(joint.find("origin")) @ in_link
        link = up[0]
        mass, moment = _subtree_mass(tree, link, np.eye(4), angles)
    inverse = np.linalg.inv(in_link)
    return Tool(frame, link, in_link, float(mass), inverse[:3, :3] @ (moment / mass) + inverse[:3, 3])
