"""The MJCF text checked before pinocchio reads it: what pinocchio would pass over or carry into the URDF.

pinocchio reads a non-finite number or a negative mass as written, and passes over a
missing mesh file or a second body in ``<worldbody>`` without a word: each is refused
here in one line naming the element.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from posegen.draft.urdf_check import number, numbers
from posegen.errors import ConfigError

_NUMBERS = (  # attributes that hold numbers, on any element of the model
    "pos", "quat", "axisangle", "euler", "xyaxes", "zaxis", "axis", "fromto", "size", "mass", "diaginertia",
    "fullinertia", "range", "ref", "scale", "density",
)  # fmt: skip


def check_numbers(root: ET.Element, path: Path) -> None:
    """Every number of the model finite, no mass negative (pinocchio reads both, and carries them into the URDF).

    Raises:
        ConfigError: The element and attribute named.

    Example:
        >>> check_numbers(ET.fromstring('<mujoco><body pos="0 nan 0"/></mujoco>'), Path("robot.xml"))
        Traceback (most recent call last):
        posegen.errors.ConfigError: robot.xml: <body name="(unnamed)"> pos="0 nan 0": expected finite numbers

    """
    for element in root.iter():
        if element.get("mass") is not None and number(element.get("mass")) < 0.0:
            raise ConfigError(f'{path}: <{element.tag}> mass="{element.get("mass")}": a negative mass (kg)')
        for key in _NUMBERS:
            text = element.get(key)
            if text is None:
                continue
            values = numbers(text)
            if not values or not np.isfinite(values).all():
                name = element.get("name") or element.get("mesh") or "(unnamed)"
                raise ConfigError(f'{path}: <{element.tag} name="{name}"> {key}="{text}": expected finite numbers')


def check_elements(root: ET.Element, path: Path) -> None:
    """Meshes that exist, one body in ``<worldbody>`` (pinocchio passes over the others without a word).

    ``root`` is the flattened MJCF (its compiler's ``meshdir`` absolute).

    Raises:
        ConfigError: The mesh or body named.

    Example:
        >>> check_elements(flattened_mjcf(Path("humanoid.xml")), Path("humanoid.xml"))  # doctest: +SKIP

    """
    meshdir = Path(next(c.get("meshdir", "") for c in root.findall("compiler") if c.get("meshdir")))  # absolute
    meshes = {}
    inline = {m.get("name") for m in root.iter("mesh") if not m.get("file")}  # vertex="...": no file to convert
    for mesh in root.iter("mesh"):
        if mesh.get("file"):
            meshes[mesh.get("name") or Path(mesh.get("file", "")).stem] = mesh.get("file", "")
    for geom in root.iter("geom"):
        name = geom.get("mesh")
        if name is not None and name not in meshes and name in inline:
            raise ConfigError(
                f"{path}: mesh '{name}' is given inline (vertex=...), not as a file: posegen converts mesh files; "
                "save it as an STL or OBJ file and name it with file=..."
            )
        if name is not None and name not in meshes:
            raise ConfigError(f"{path}: geom '{geom.get('name', '(unnamed)')}' names the mesh '{name}', not in <asset>")
        if name is not None and not (meshdir / meshes[name]).is_file():
            raise ConfigError(f"{path}: mesh '{name}' file '{meshes[name]}' not found in {meshdir}")
    bodies = [body for world in root.findall("worldbody") for body in world.findall("body")]
    if not bodies:
        raise ConfigError(f"{path}: no body in <worldbody>")
    if len(bodies) > 1:
        second = bodies[1].get("name", "(unnamed)")
        raise ConfigError(f"{path}: a second body '{second}' in <worldbody>; posegen reads one robot: remove it")
