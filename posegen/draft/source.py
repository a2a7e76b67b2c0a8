"""The robot ``posegen robot init`` studies: an example-robot-data name or a URDF file.

(An MJCF model is converted to a URDF first, by :mod:`posegen.draft.mjcf_source`.)

Whatever is wrong with it is said in one line naming the file and the element: a file
that is missing or not XML, a folder, a malformed URDF (:mod:`posegen.draft.urdf_check`:
not one tree, numbers that are not finite, no mass), a URDF pinocchio cannot load (what
its parser printed kept off the terminal, its cause in the message), a mesh that cannot be found
(relative paths are read from the URDF's folder, ``package://`` ones from the package
dirs and from the folders above the URDF named like the package).
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import pinocchio as pin

from posegen.draft.mjcf import MJCF_ROOT
from posegen.draft.urdf_check import check_urdf
from posegen.errors import ConfigError
from posegen.io import native_output
from posegen.robot import PACKAGE_URI, RobotFiles, RobotSource, package_uri, resolve_path, resolve_source


@dataclass(frozen=True)
class DraftSource:
    """The description a draft is made from."""

    source: RobotSource  # as the config will name it
    files: RobotFiles
    text: str  # the URDF, relative mesh paths made absolute
    model: pin.Model  # with a free-flyer root

    @property
    def label(self) -> str:
        """The robot's name in messages: its example-robot-data name or its URDF file."""
        return self.source.example_robot_data or str(self.files.urdf)


def load_draft_source(name: str, srdf: str | None = None, package_dirs: tuple[str, ...] = ()) -> DraftSource:
    """Load the robot named by ``name``: an example-robot-data robot, or a URDF file (a path or ``package://``).

    Raises:
        ConfigError: Unknown name, a file that is missing or is not a URDF pinocchio
            loads, an MJCF file, or a mesh that cannot be found (file and link named).

    """
    path = resolve_path(name, package_dirs) if name.startswith(PACKAGE_URI) else Path(name)
    bare = "/" not in name and os.sep not in name and not path.suffix  # example-robot-data's, whatever folder is here
    if path.is_dir() and not bare:
        raise ConfigError(f"{name}: a folder; give a URDF or MJCF file (or an example-robot-data name)")
    if path.suffix.lower() in (".urdf", ".xml", ".mjcf") or path.is_file():
        if not path.is_file():
            raise ConfigError(f"{name}: file not found")
        absolute = path.resolve()
        source = RobotSource(
            urdf=package_uri(absolute) or str(absolute),  # a description installed from PyPI: portable
            srdf=None if srdf is None else str(Path(srdf).resolve()) if not srdf.startswith(PACKAGE_URI) else srdf,
            package_dirs=tuple(str(Path(d).resolve()) for d in package_dirs),
        )
        root = _xml_root(absolute)
        if root.tag == MJCF_ROOT:
            raise ConfigError(f"{name}: an MJCF model; posegen's stages read a URDF: `posegen robot init` converts it")
        if root.tag != "robot":
            raise ConfigError(f"{name}: not a URDF (its root element is <{root.tag}>, not <robot>)")
    else:
        source = RobotSource(example_robot_data=name, srdf=srdf, package_dirs=package_dirs)
    files = resolve_source(source)
    text = files.urdf_text()
    check_urdf(text, files.urdf)
    check_meshes(files.urdf, text, files.package_dirs)
    with native_output() as printed:  # urdfdom's own lines, kept: the message says the cause
        try:
            model = pin.buildModelFromXML(text, pin.JointModelFreeFlyer())
        except (RuntimeError, ValueError) as exc:
            error: Exception | None = exc
        else:
            error = None
    if error is not None:
        said = printed.cause()
        raise ConfigError(
            f"{files.urdf}: pinocchio cannot load it: {_first_line(error)}" + (f" ({said})" if said else "")
        ) from error
    return DraftSource(source, files, text, model)


def source_files(name: str, srdf: str | None = None, package_dirs: tuple[str, ...] = ()) -> tuple[Path, ...]:
    """The files a draft of ``name`` reads: its URDF, SRDF and every mesh they name (those that exist).

    None of them may be an output of ``robot init``. A description that cannot be read
    yields what was found so far (its loading says what is wrong with it, in order).

    Example:
        >>> source_files("robot.urdf")  # doctest: +SKIP
        (PosixPath('/robots/robot.urdf'), PosixPath('/robots/meshes/foot.stl'))

    """
    path = resolve_path(name, package_dirs) if name.startswith(PACKAGE_URI) else Path(name)
    local = path.is_file()
    source = (
        RobotSource(urdf=str(path.resolve()), srdf=srdf, package_dirs=package_dirs)
        if local
        else RobotSource(example_robot_data=name, srdf=srdf, package_dirs=package_dirs)
    )
    found = [path] if local else []
    try:
        files = resolve_source(source)
        found += [files.urdf, *([files.srdf] if files.srdf else [])]
        root = ET.fromstring(files.urdf_text())
    except (ConfigError, ET.ParseError):
        return tuple(found)
    for mesh in root.iter("mesh"):
        filename = str(mesh.get("filename", ""))
        if filename.startswith(PACKAGE_URI):
            relative = filename[len(PACKAGE_URI) :].lstrip("/")
            found += [Path(d) / relative for d in files.package_dirs if (Path(d) / relative).is_file()]
        elif os.path.isfile(filename.removeprefix("file://")):
            found.append(Path(filename.removeprefix("file://")))
    return tuple(dict.fromkeys(found))


def _xml_root(path: Path) -> ET.Element:
    try:
        return ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise ConfigError(f"{path}: not valid XML ({exc})") from exc
    except OSError as exc:
        raise ConfigError(f"{path}: cannot be read ({exc.strerror})") from exc


def check_meshes(urdf: Path, text: str, package_dirs: tuple[str, ...]) -> None:
    """Check that every mesh of the URDF's links can be found.

    Raises:
        ConfigError: The first mesh not found, with its link and the places looked in.

    """
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ConfigError(f"{urdf}: not valid XML ({exc})") from exc
    for link in root.findall("link"):
        for kind in ("collision", "visual"):
            for mesh in link.findall(f"{kind}/geometry/mesh"):
                filename = str(mesh.get("filename", ""))
                if not _mesh_found(filename, package_dirs):
                    where = f"package dirs {', '.join(package_dirs) or '(none)'}" if PACKAGE_URI in filename else ""
                    raise ConfigError(
                        f"{urdf}: link '{link.get('name')}' {kind} mesh '{filename}' not found"
                        + (f" (looked in {where}; add package_dirs)" if where else ""),
                        parameter="package_dirs" if where else None,
                    )


def _mesh_found(filename: str, package_dirs: tuple[str, ...]) -> bool:
    if filename.startswith(PACKAGE_URI):
        relative = filename[len(PACKAGE_URI) :].lstrip("/")  # package:///NAME/... is seen too
        return any(os.path.isfile(os.path.join(d, relative)) for d in package_dirs)
    if filename.startswith("file://"):
        filename = filename[len("file://") :]
    return os.path.isfile(filename)


def _first_line(exc: Exception) -> str:
    lines = str(exc).strip().splitlines()
    return lines[0] if lines else type(exc).__name__
