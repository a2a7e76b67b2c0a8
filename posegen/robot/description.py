"""The robot description: its files, and the URDF posegen derives from them.

posegen adds one *contact frame* per chain to the robot description: the centroid of
the fingertip ends, with z along the gripper normal (pointing away from the table at a
flush contact). pinocchio, placo and the calibration model all read the same augmented
URDF, so every stage agrees on where the contact is.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError, unknown_name
from posegen.io import read_text_file
from posegen.robot.additions import FrameConfig
from posegen.robot.config import PACKAGE_URI, Config, RobotSource
from posegen.robot.contact_kinds.flush import contact_placement
from posegen.robot.geometry import FloatArray
from posegen.robot.geometry import frame_id as frame_id  # now in geometry (flush contacts use it); scene reads it here


@dataclass(frozen=True)
class RobotFiles:
    """Resolved robot description files."""

    urdf: Path
    srdf: Path | None  # None: no SRDF (reference posture and disabled pairs from the config)
    package_dirs: tuple[str, ...]

    def sha256(self) -> str:
        """Hash of the URDF and SRDF contents (the model identity saved in artefacts)."""
        digest = hashlib.sha256()
        for path in (self.urdf, self.srdf):
            if path is not None:
                digest.update(path.read_bytes())
        return digest.hexdigest()

    def srdf_path(self) -> str | None:
        """The SRDF's path as text, or None without one."""
        return None if self.srdf is None else str(self.srdf)

    def urdf_text(self) -> str:
        """The URDF's text, its relative mesh paths made absolute (from the URDF's folder).

        Raises:
            ConfigError: The file cannot be read as text.

        """
        return absolute_mesh_paths(read_text_file(self.urdf, ConfigError), self.urdf.parent)


def resolve_robot_files(config: Config) -> RobotFiles:
    """Find the URDF/SRDF files named by the config (see :func:`resolve_source`)."""
    return resolve_source(config.robot)


def resolve_source(source: RobotSource) -> RobotFiles:
    """Find the URDF/SRDF files of a robot source.

    An example-robot-data robot is named as ``example_robot_data.load`` names it. Its
    SRDF is the loader's unless ``srdf`` names another (a path, or a ``package://`` URI
    resolved in the package dirs); it may have none. A URDF's ``package://NAME/`` mesh
    paths are also looked up beside a folder NAME above the URDF (the ROS layout).

    Raises:
        ConfigError: The files do not exist or the robot name is unknown.

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
        srdf: Path | None
        if source.srdf is not None:
            srdf = resolve_path(source.srdf, package_dirs)
        else:
            srdf = data_dir / loader.srdf_subpath / loader.srdf_filename if loader.srdf_filename else None
    else:
        urdf = resolve_path(str(source.urdf), source.package_dirs)
        package_dirs = (*source.package_dirs, *_ancestor_package_dirs(urdf))
        srdf = None if source.srdf is None else resolve_path(source.srdf, package_dirs)
    for path in (urdf, srdf):
        if path is not None and not path.is_file():
            raise ConfigError(f"robot.source: file not found: {path}")
    return RobotFiles(urdf=urdf, srdf=srdf, package_dirs=package_dirs)


def _ancestor_package_dirs(urdf: Path) -> tuple[str, ...]:
    """Folders above the URDF that hold a package its ``package://NAME/`` paths name."""
    if not urdf.is_file():
        return ()
    names = set(re.findall(r"package://([^/\s\"']+)/", urdf.read_text(errors="replace")))
    found = []
    for folder in urdf.resolve().parents:
        if folder.name in names and str(folder.parent) not in found:
            found.append(str(folder.parent))
    return tuple(found)


def absolute_mesh_paths(urdf_text: str, folder: Path) -> str:
    """The URDF text with its relative mesh file names made absolute (relative to ``folder``).

    ``package://`` and ``file://`` URIs and absolute paths are left as they are.
    """

    def fix(match: re.Match[str]) -> str:
        name = match.group(2)
        if "://" in name or Path(name).is_absolute():
            return match.group(0)
        return f"{match.group(1)}{(folder / name).resolve()}{match.group(3)}"

    return re.sub(r"(<mesh\b[^>]*?\bfilename\s*=\s*[\"'])([^\"']+)([\"'])", fix, urdf_text)


def resolve_path(path: str, package_dirs: tuple[str, ...]) -> Path:
    """A file path, or a ``package://NAME/...`` URI looked up in the package dirs, else in Python package NAME.

    A description installed from PyPI (``pip install NAME``) is its own package dir.
    """
    if not path.startswith(PACKAGE_URI):
        return Path(path)
    relative = path[len(PACKAGE_URI) :]
    for directory in (*package_dirs, *python_package_parent(relative.split("/")[0])):
        candidate = Path(directory) / relative
        if candidate.is_file():
            return candidate
    return Path(package_dirs[0] if package_dirs else ".") / relative  # reported as not found


def python_package_parent(name: str) -> tuple[str, ...]:
    """The folder holding an installed Python package called ``name`` (none if there is no such package)."""
    if not name.isidentifier():
        return ()
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return ()
    if spec is None or not spec.submodule_search_locations:
        return ()
    return tuple(str(Path(location).parent) for location in spec.submodule_search_locations)


def package_uri(path: Path) -> str | None:
    """``package://NAME/...`` for a file inside an installed Python package NAME, else None.

    Installed: a regular package (with its ``__init__.py``) in a ``site-packages`` or
    ``dist-packages`` folder. A folder that Python only finds because it sits in the
    current or the script's folder (a namespace package) is not one: another process,
    started elsewhere, would not find it.

    Example:
        >>> package_uri(Path(jvrc_description.__file__).parent / "urdf" / "jvrc1.urdf")
        'package://jvrc_description/urdf/jvrc1.urdf'

    """
    resolved = path.resolve()
    for folder in resolved.parents:
        if str(folder.parent) in python_package_parent(folder.name) and _installed(folder):
            return f"{PACKAGE_URI}{resolved.relative_to(folder.parent).as_posix()}"
    return None


def _installed(folder: Path) -> bool:
    """Whether a package's folder is an installed regular package (see :func:`package_uri`)."""
    return (folder / "__init__.py").is_file() and bool({"site-packages", "dist-packages"} & set(folder.parts))


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
