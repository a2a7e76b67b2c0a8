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
from posegen.robot.config import ChainConfig, Config


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
    """Find the URDF/SRDF files named by the config.

    Raises:
        ConfigError: The files do not exist or the example-robot-data name is unknown.

    """
    source = config.robot
    if source.example_robot_data is not None:
        from example_robot_data import robots_loader

        loaders = {
            name[: -len("Loader")].lower(): cls
            for name, cls in vars(robots_loader).items()
            if name.endswith("Loader") and isinstance(cls, type) and getattr(cls, "urdf_filename", "")
        }
        key = source.example_robot_data.lower()
        if key not in loaders:
            raise ConfigError(unknown_name("example-robot-data robot", key, loaders))
        loader: Any = loaders[key]
        robots_dir = Path(robots_loader.getModelPath(loader.path))
        data_dir = robots_dir / loader.path
        urdf = data_dir / loader.urdf_subpath / loader.urdf_filename
        srdf = data_dir / loader.srdf_subpath / loader.srdf_filename
        package_dirs: tuple[str, ...] = (os.path.normpath(robots_dir / ".." / ".."),)
    else:
        urdf = Path(str(source.urdf))
        srdf = Path(str(source.srdf))
        package_dirs = source.package_dirs
    for path in (urdf, srdf):
        if not path.is_file():
            raise ConfigError(f"robot.source: file not found: {path}")
    return RobotFiles(urdf=urdf, srdf=srdf, package_dirs=package_dirs)


def frame_id(model: pin.Model, name: str) -> int:
    """Pinocchio id of a frame.

    Raises:
        ConfigError: No such frame (the valid ones are listed).

    """
    if not model.existFrame(name):
        raise ConfigError(unknown_name("frame", name, (f.name for f in model.frames)))
    return int(model.getFrameId(name))


def contact_placement(model: pin.Model, chain: ChainConfig) -> pin.SE3:
    """Placement of a chain's contact frame in its gripper frame.

    Origin: centroid of the fingertip ends (each ``fingertip_length_m`` beyond its link
    origin, against the normal). z: normal of the fingertip plane, pointing to the side
    of the gripper frame origin. x: the gripper frame's x projected on the plane.
    """
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model))
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


def augmented_urdf(urdf_text: str, model: pin.Model, config: Config) -> str:
    """The URDF with one fixed contact link per chain added."""
    root = ET.fromstring(urdf_text)
    for chain in config.chains:
        placement = contact_placement(model, chain)
        xyz = " ".join(repr(float(v)) for v in placement.translation)
        rpy = " ".join(repr(float(v)) for v in pin.rpy.matrixToRpy(placement.rotation))
        ET.SubElement(root, "link", name=chain.contact_frame)
        joint = ET.SubElement(root, "joint", name=f"{chain.contact_frame}_joint", type="fixed")
        ET.SubElement(joint, "parent", link=chain.gripper_frame)
        ET.SubElement(joint, "child", link=chain.contact_frame)
        ET.SubElement(joint, "origin", xyz=xyz, rpy=rpy)
    return ET.tostring(root, encoding="unicode")


def kinematic_urdf(urdf_text: str) -> str:
    """The URDF without visual and collision elements (what solvers need)."""
    root = ET.fromstring(urdf_text)
    for link in root.findall("link"):
        for tag in ("visual", "collision"):
            for element in link.findall(tag):
                link.remove(element)
    return ET.tostring(root, encoding="unicode")
