"""An MJCF's joints as each body holds them: their names, and their ``ref`` as MuJoCo resolves it.

A joint's ``ref`` is its angle (or a slide's position) in the pose the model is written
in. pinocchio's MJCF parser puts a joint's zero there, while MuJoCo's zero (the angle a
robot's encoders report, and the one its ``range`` is given in) is ``ref`` away from it:
the converted URDF turns each joint's origin back by its ``ref`` (:func:`joint_refs`).

An attribute a joint does not give comes from its class's defaults: its ``class``, else
the ``childclass`` of the nearest body around it (its own included), else ``main``; a
class's defaults are its ``<joint>`` attributes over those of the classes it is nested in.
A hinge's ``ref`` is in degrees unless the ``<compiler>`` says ``angle="radian"``.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

from posegen.errors import ConfigError

MAIN_CLASS = "main"


def body_joint_names(root: ET.Element) -> dict[str, list[str]]:
    """The names of each named body's ``<joint>`` elements, in order (unnamed: ``<body>_joint<k>``).

    Example:
        >>> body_joint_names(ET.fromstring('<mujoco><worldbody><body name="arm"><joint/></body></worldbody></mujoco>'))
        {'arm': ['arm_joint0']}

    """
    names: dict[str, list[str]] = {}
    for body in root.iter("body"):
        name = body.get("name")
        if name is not None:
            joints = body.findall("joint")
            names[name] = [j.get("name") or f"{name}_joint{k}" for k, j in enumerate(joints)]
    return names


def joint_defaults(root: ET.Element) -> dict[str, dict[str, str]]:
    """Each default class's ``<joint>`` attributes, those of the classes it is nested in included.

    Example:
        >>> leg = '<default class="leg"><joint axis="0 1 0"/></default>'
        >>> joint_defaults(ET.fromstring(f'<mujoco><default><joint ref="1"/>{leg}</default></mujoco>'))["leg"]
        {'ref': '1', 'axis': '0 1 0'}

    """
    classes: dict[str, dict[str, str]] = {}

    def visit(element: ET.Element, inherited: dict[str, str]) -> None:
        own = dict(inherited)
        for joint in element.findall("joint"):
            own.update(joint.attrib)
        classes[element.get("class", MAIN_CLASS)] = own
        for child in element.findall("default"):
            visit(child, own)

    for top in root.findall("default"):
        visit(top, {})
    return classes


def joint_refs(root: ET.Element, path: Path) -> dict[str, list[float]]:
    """Each named body's joints' ``ref``, in order: rad for a hinge, m for a slide.

    Args:
        root: The flattened MJCF (includes inlined, frames made bodies).
        path: The MJCF file, named in errors.

    Raises:
        ConfigError: A joint with a nonzero ``ref`` is in a body without a name (its
            converted joint could not be told apart), or names a class no default defines.

    Example:
        >>> text = '<mujoco><worldbody><body name="b"><joint ref="90"/></body></worldbody></mujoco>'
        >>> joint_refs(ET.fromstring(text), Path("robot.xml"))  # degrees by default
        {'b': [1.5707963267948966]}

    """
    classes = joint_defaults(root)
    degrees = _angle_unit(root) != "radian"
    refs: dict[str, list[float]] = {}

    def visit(body: ET.Element, childclass: str) -> None:
        childclass = body.get("childclass", childclass)
        values = []
        for joint in body.findall("joint"):
            kind = joint.get("class", childclass)
            if kind not in classes and kind != MAIN_CLASS:
                raise ConfigError(f"{path}: joint class '{kind}' has no <default class=\"{kind}\">")
            attributes = {**classes.get(kind, {}), **joint.attrib}
            ref = float(attributes.get("ref", "0"))
            hinge = attributes.get("type", "hinge") == "hinge"
            values.append(math.radians(ref) if hinge and degrees else ref)
        name = body.get("name")
        if name is not None:
            refs[name] = values
        elif any(values):
            raise ConfigError(f"{path}: a body with a joint whose ref is not 0 has no name; name it")
        for child in body.findall("body"):
            visit(child, childclass)

    for world in root.findall("worldbody"):
        for body in world.findall("body"):
            visit(body, MAIN_CLASS)
    return refs


def _angle_unit(root: ET.Element) -> str:
    """The compiler's angle unit (MuJoCo's default: degree); the last ``<compiler>`` that gives one."""
    unit = "degree"
    for compiler in root.findall("compiler"):
        unit = compiler.get("angle", unit)
    return unit
