"""The MJCF text pinocchio is given: includes inlined, assets in one section, folders absolute.

pinocchio 3.8 builds a model's kinematics through ``<include>`` elements, but its geometry
reader does not see the assets an included file defines (a ``material="self"`` from an
included ``materials.xml`` fails with ``unordered_map::at``, as in dm_control's humanoid),
and it reads the first ``<asset>`` section only. So the model is flattened first: each
``<include>`` is replaced by the children of the included file's ``<mujoco>`` (paths
relative to the main file's folder, as MuJoCo reads them), the ``<frame>`` elements (which
pinocchio skips, with every body in them) become bodies without joints, each joint's and
geom's attributes from its class are written on it (pinocchio skips a class's ``pos`` and
lays a body's ``childclass`` over an element's ``class``), each ``axisangle``'s axis is made of
unit length (MuJoCo normalizes it, pinocchio does not), each ``euler`` becomes the ``quat``
MuJoCo makes of it (pinocchio turns an upper-case ``eulerseq``, about the fixed axes, as a
lower-case one), the ``<asset>`` sections are merged into one, and the compiler's
``meshdir``, ``texturedir`` and ``assetdir`` are made absolute, so that the flattened text
can be read from any folder.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

from posegen.draft.mjcf_classes import write_resolved
from posegen.errors import ConfigError

MAX_INCLUDE_DEPTH = 16  # deeper is a cycle
_ASSET_DIRS = ("meshdir", "texturedir", "assetdir")


def parse_xml(path: Path) -> ET.Element:
    """The root element of an XML file.

    Example:
        >>> parse_xml(Path("humanoid.xml")).tag  # doctest: +SKIP
        'mujoco'

    Raises:
        ConfigError: The file cannot be read or is not XML (the file named).

    """
    try:
        return ET.parse(path).getroot()
    except OSError as exc:
        raise ConfigError(f"{path}: cannot be read ({exc.strerror})") from exc
    except ET.ParseError as exc:
        raise ConfigError(f"{path}: not valid XML ({exc})") from exc


def flattened_mjcf(path: Path) -> ET.Element:
    """The MJCF model at ``path`` with its includes inlined and its asset folders absolute.

    Raises:
        ConfigError: The file or an included one cannot be read or is not XML, an include
            is missing, or includes nest deeper than :data:`MAX_INCLUDE_DEPTH` (a cycle).

    Example:
        >>> root = flattened_mjcf(Path("dm_control/suite/humanoid.xml"))  # doctest: +SKIP
        >>> root.find("asset/material").get("name")  # doctest: +SKIP
        'grid'

    """
    root = parse_xml(path)
    _inline(root, path, 0)
    _frames_as_bodies(root)
    write_resolved(root, path)
    _unit_rotation_axes(root)
    _euler_as_quaternion(root)
    _one_asset_section(root)
    _absolute_asset_dirs(root, path.parent)
    return root


def _frames_as_bodies(root: ET.Element) -> None:
    """Replace each ``<frame>`` by what pinocchio reads (its MJCF parser skips a frame and all it holds).

    In a body, a frame becomes a body without joints (welded to its parent, placed by the
    frame's pose, its ``childclass`` kept); in ``<worldbody>``, its elements move up in its
    place (the root floats: the frame's pose would only place it), inheriting its
    ``childclass`` as their own class when they have none.
    """
    for world in root.findall("worldbody"):
        while (frame := world.find("frame")) is not None:
            at = list(world).index(frame)
            world.remove(frame)
            for k, child in enumerate(list(frame)):
                kind = "childclass" if child.tag in ("body", "frame") else "class"
                if frame.get("childclass") is not None and child.get(kind) is None:
                    child.set(kind, frame.get("childclass", ""))
                world.insert(at + k, child)
    taken = {b.get("name") for b in root.iter("body")}
    for k, frame in enumerate(root.iter("frame")):
        frame.tag = "body"
        name = frame.get("name") or f"frame_{k}"
        while name in taken:
            name += "_frame"
        frame.set("name", name)
        taken.add(name)


def _unit_rotation_axes(root: ET.Element) -> None:
    """Normalize each ``axisangle``'s axis, as MuJoCo does (pinocchio takes it as written: a wrong turn)."""
    for element in root.iter():
        values = element.get("axisangle", "").split()
        try:
            x, y, z, angle = (float(v) for v in values)
        except ValueError:
            continue  # absent, or not four numbers: MuJoCo's own message (the conversion reads it as written)
        norm = math.sqrt(x * x + y * y + z * z)
        if norm > 0.0 and math.isfinite(norm):
            element.set("axisangle", f"{x / norm!r} {y / norm!r} {z / norm!r} {angle!r}")


def _euler_as_quaternion(root: ET.Element) -> None:
    """Write each ``euler`` as the ``quat`` MuJoCo makes of it (pinocchio turns an upper-case ``eulerseq`` wrongly).

    MuJoCo turns about each axis of the compiler's ``eulerseq`` in turn (default ``xyz``):
    about the moving frame's axis for a lower-case letter, about the fixed frame's for an
    upper-case one; the angles are in the compiler's unit (default degrees).
    """
    sequence, unit = "xyz", "degree"
    for compiler in root.findall("compiler"):
        sequence, unit = compiler.get("eulerseq", sequence), compiler.get("angle", unit)
    scale = 1.0 if unit == "radian" else math.pi / 180.0
    for element in root.iter():
        values = element.get("euler", "").split()
        try:
            angles = [float(v) * scale for v in values]
        except ValueError:
            continue  # not numbers: MuJoCo's own message (the conversion reads it as written)
        if len(angles) != 3 or len(sequence) != 3 or not set(sequence.lower()) <= set("xyz"):
            continue
        total = (1.0, 0.0, 0.0, 0.0)  # (w, x, y, z)
        for letter, angle in zip(sequence, angles, strict=True):
            turn = [math.cos(angle / 2.0), 0.0, 0.0, 0.0]
            turn[1 + "xyz".index(letter.lower())] = math.sin(angle / 2.0)
            total = _product(total, tuple(turn)) if letter.islower() else _product(tuple(turn), total)
        del element.attrib["euler"]
        element.set("quat", " ".join(repr(v) for v in total))


def _product(a: tuple[float, ...], b: tuple[float, ...]) -> tuple[float, float, float, float]:
    """The quaternion product ``a b``, (w, x, y, z)."""
    return (
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    )


def _one_asset_section(root: ET.Element) -> None:
    """Merge the top-level ``<asset>`` sections into the first (pinocchio reads the first one only)."""
    sections = root.findall("asset")
    for section in sections[1:]:
        sections[0].extend(list(section))
        root.remove(section)


def _inline(element: ET.Element, path: Path, depth: int) -> None:
    """Replace each ``<include>`` under ``element`` by the included file's elements (recursively)."""
    children = list(element)
    for child in children:
        element.remove(child)
    for child in children:
        if child.tag != "include":
            _inline(child, path, depth)
            element.append(child)
            continue
        name = child.get("file", "")
        included = path.parent / name
        if not included.is_file():
            raise ConfigError(f'{path}: <include file="{name}"> not found beside it')
        if depth >= MAX_INCLUDE_DEPTH:
            raise ConfigError(f'{path}: <include file="{name}"> nests {depth} deep: includes form a cycle')
        inner = parse_xml(included)
        _inline(inner, path, depth + 1)  # MuJoCo reads every include from the main file's folder
        element.extend(list(inner))


def _absolute_asset_dirs(root: ET.Element, folder: Path) -> None:
    """Make the compiler's asset folders absolute (a compiler element is added if there is none)."""
    compilers = root.findall("compiler")
    if not compilers:
        compilers = [ET.Element("compiler")]
        root.insert(0, compilers[0])
    for compiler in compilers:
        for key in _ASSET_DIRS:
            if compiler.get(key) is not None:
                compiler.set(key, str((folder / compiler.get(key, "")).resolve()))
    base = next((c.get("assetdir", "") for c in compilers if c.get("assetdir")), str(folder.resolve()))
    for key in ("meshdir", "texturedir"):
        if not any(c.get(key) for c in compilers):
            compilers[0].set(key, base)
