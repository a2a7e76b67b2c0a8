"""The robot description: its files, and the URDF posegen derives from them.

posegen adds one *contact frame* per chain to the robot description: the centroid of
the fingertip ends, with z along the gripper normal (pointing away from the table at a
flush contact). pinocchio, placo and the calibration model all read the same augmented
URDF, so every stage agrees on where the contact is.
"""

from __future__ import annotations

import hashlib
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError, unknown_name
from posegen.robot.additions import FrameConfig
from posegen.robot.config import PACKAGE_URI, ChainConfig, Config, RobotSource
from posegen.robot.geometry import FloatArray


@dataclass(frozen=True)
class RobotFiles:
    """Resolved robot description files."""

    urdf: Path
    srdf: Path
    package_dirs: tuple[str, ...]

    def sha256(self) -> str:
        """Hash of the URDF and SRDF contents (the model identity saved in artefacts)."""
        digest = hashlib.sha256()
        for path in (self.urdf, self.srdf):
            digest.update(path.read_bytes())
        return digest.hexdigest()


def resolve_robot_files(config: Config) -> RobotFiles:
    """Find the URDF/SRDF files named by the config (see :func:`resolve_source`)."""
    return resolve_source(config.robot)


def resolve_source(source: RobotSource) -> RobotFiles:
    """Find the URDF/SRDF files of a robot source.

    An example-robot-data robot is named as ``example_robot_data.load`` names it. Its
    SRDF is the loader's unless ``srdf`` names another (a path, or a ``package://`` URI
    resolved in the package dirs).

    Raises:
        ConfigError: The files do not exist, the robot name is unknown or has no SRDF.

    """
    if source.example_robot_data is not None:
        from example_robot_data import robots_loader

        loaders = dict(robots_loader.ROBOTS)
        key = source.example_robot_data
        if key not in loaders:
            raise ConfigError(unknown_name("example-robot-data robot", key, loaders))
        loader: Any = loaders[key]
        robots_dir = Path(robots_loader.getModelPath(loader.path))
        data_dir = Path(os.path.normpath(robots_dir / loader.path))
        urdf = data_dir / loader.urdf_subpath / loader.urdf_filename
        package_dirs: tuple[str, ...] = (os.path.normpath(robots_dir / ".." / ".."), *source.package_dirs)
        if source.srdf is not None:
            srdf = _resolve(source.srdf, package_dirs)
        elif loader.srdf_filename:
            srdf = data_dir / loader.srdf_subpath / loader.srdf_filename
        else:
            found = sorted(p.name for p in (data_dir / loader.srdf_subpath).glob("*.srdf"))
            raise ConfigError(
                f"robot.source.srdf: example-robot-data '{key}' has no SRDF of its own; name one "
                f"(files in {data_dir / loader.srdf_subpath}: {', '.join(found) or 'none'})"
            )
    else:
        package_dirs = source.package_dirs
        urdf = _resolve(str(source.urdf), package_dirs)
        srdf = _resolve(str(source.srdf), package_dirs)
    for path in (urdf, srdf):
        if not path.is_file():
            raise ConfigError(f"robot.source: file not found: {path}")
    return RobotFiles(urdf=urdf, srdf=srdf, package_dirs=package_dirs)


def _resolve(path: str, package_dirs: tuple[str, ...]) -> Path:
    """A file path, or a ``package://NAME/...`` URI looked up in the package dirs."""
    if not path.startswith(PACKAGE_URI):
        return Path(path)
    relative = path[len(PACKAGE_URI) :]
    for directory in package_dirs:
        candidate = Path(directory) / relative
        if candidate.is_file():
            return candidate
    return Path(package_dirs[0] if package_dirs else ".") / relative  # reported as not found


def frame_id(model: pin.Model, name: str) -> int:
    """Pinocchio id of a frame.

    Raises:
        ConfigError: No such frame (the valid ones are listed).

    """
    if not model.existFrame(name):
        raise ConfigError(unknown_name("frame", name, (f.name for f in model.frames)))
    return int(model.getFrameId(name))


def locked_configuration(model: pin.Model, locked: dict[str, float]) -> FloatArray:
    """The model's neutral configuration with the locked joints at their values. Shape (nq,).

    Raises:
        ConfigError: A locked joint is not a 1-dof joint of the model (the valid ones are listed).

    """
    q = pin.neutral(model)
    joints = [str(model.names[j]) for j in range(1, model.njoints) if model.joints[j].nq == 1]
    for name, value in locked.items():
        if name not in joints:
            raise ConfigError(unknown_name("joint", name, joints) + " (robot.locked_joints)")
        q[model.joints[model.getJointId(name)].idx_q] = value
    return q


def contact_placement(model: pin.Model, chain: ChainConfig, q: FloatArray | None = None) -> pin.SE3:
    """Placement of a chain's contact frame in its gripper frame.

    Origin: centroid of the fingertip ends (each ``fingertip_length_m`` beyond its link
    origin, against the normal). z: normal of the fingertip plane, pointing to the side
    of the gripper frame origin. x: the gripper frame's x projected on the plane.

    Args:
        model: The robot model.
        chain: The chain.
        q: Configuration the fingertips are read at (locked finger joints matter);
            None for the neutral one. Shape (nq,).

    """
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model) if q is None else q)
    grip = data.oMf[frame_id(model, chain.gripper_frame)]
    tips = np.array([grip.actInv(data.oMf[frame_id(model, f)]).translation for f in chain.fingertip_frames])  # (n, 3)
    centroid = tips.mean(axis=0)
    normal = np.linalg.svd(tips - centroid)[2][-1]
    if normal @ (-centroid) < 0:
        normal = -normal
    x_axis = np.array([1.0, 0.0, 0.0]) - normal[0] * normal
    if np.linalg.norm(x_axis) < 1e-6:
        x_axis = np.array([0.0, 1.0, 0.0]) - normal[1] * normal
    x_axis /= np.linalg.norm(x_axis)
    rotation = np.column_stack([x_axis, np.cross(normal, x_axis), normal])
    return pin.SE3(rotation, centroid - chain.fingertip_length_m * normal)


def with_declared_frames(urdf_text: str, model: pin.Model, frames: tuple[FrameConfig, ...]) -> str:
    """The URDF with the config's declared frames added as fixed links.

    Raises:
        ConfigError: A declared frame exists already or its parent is not a link.

    """
    if not frames:
        return urdf_text
    root = ET.fromstring(urdf_text)
    links = {str(link.get("name")) for link in root.findall("link")}
    for frame in frames:
        if model.existFrame(frame.name) or frame.name in links:
            raise ConfigError(f"robot.frames.{frame.name}: the robot already has a frame of that name")
        if frame.parent not in links:
            raise ConfigError(unknown_name("link", frame.parent, links) + f" (robot.frames.{frame.name}.parent)")
        _add_fixed_link(root, frame.name, frame.parent, np.array(frame.xyz_m), np.deg2rad(frame.rpy_deg))
        links.add(frame.name)
    return ET.tostring(root, encoding="unicode")


def augmented_urdf(urdf_text: str, model: pin.Model, config: Config, q: FloatArray | None = None) -> str:
    """The URDF with one fixed flush contact link per chain added (fingertips read at ``q``)."""
    root = ET.fromstring(urdf_text)
    for chain in config.chains:
        if not chain.fingertip_frames:
            continue  # a point-contact chain: its frame is the robot's (or declared)
        placement = contact_placement(model, chain, q)
        rpy = np.asarray(pin.rpy.matrixToRpy(placement.rotation))
        _add_fixed_link(root, chain.contact_frame, chain.gripper_frame, placement.translation, rpy)
    return ET.tostring(root, encoding="unicode")


def _add_fixed_link(root: ET.Element, name: str, parent: str, xyz: FloatArray, rpy: FloatArray) -> None:
    ET.SubElement(root, "link", name=name)
    joint = ET.SubElement(root, "joint", name=f"{name}_joint", type="fixed")
    ET.SubElement(joint, "parent", link=parent)
    ET.SubElement(joint, "child", link=name)
    ET.SubElement(
        joint,
        "origin",
        xyz=" ".join(repr(float(v)) for v in xyz),
        rpy=" ".join(repr(float(v)) for v in rpy),
    )


def kinematic_urdf(urdf_text: str) -> str:
    """The URDF without visual and collision elements (what solvers need)."""
    root = ET.fromstring(urdf_text)
    for link in root.findall("link"):
        for tag in ("visual", "collision"):
            for element in link.findall(tag):
                link.remove(element)
    return ET.tostring(root, encoding="unicode")
