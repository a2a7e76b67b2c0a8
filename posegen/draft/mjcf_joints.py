"""An MJCF's joints as MuJoCo reads them: names, ``ref`` and a slide's range, for the URDF's joints.

* ``ref``, a joint's value in the pose the model is written in: pinocchio puts the joint's
  zero there, MuJoCo ``ref`` away from it (its zero is the one the ``range`` and a robot's
  encoders use), so the converted URDF turns the joint's origin back by it (a hinge's
  ``ref`` is in degrees unless the ``<compiler>`` says ``angle="radian"``);
* a slide's ``range``, which pinocchio reads as an angle (degrees turned into radians).

Each is read through the joint's class (:mod:`posegen.draft.mjcf_classes`).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

from posegen.draft.mjcf_classes import resolved
from posegen.errors import ConfigError


@dataclass(frozen=True)
class MjcfJoint:
    """One ``<joint>`` of a body, read with its class's defaults under its own attributes."""

    name: str  # its name, or ``<body>_joint<k>``
    ref: float  # rad for a hinge, m for a slide: its value in the pose as written (pinocchio's zero)
    slide_range_m: tuple[float, float] | None  # a slide's range as written; None: a hinge, or no range


def body_joints(root: ET.Element, path: Path) -> dict[str, list[MjcfJoint]]:
    """Each named body's joints, in order (a ``ref`` in degrees read as rad).

    Args:
        root: The flattened MJCF (includes inlined, frames made bodies).
        path: The MJCF file, named in errors.

    Raises:
        ConfigError: A joint names a class no default defines, or a joint with a nonzero
            ``ref`` is in a body without a name (its converted joint could not be told apart).

    Example:
        >>> text = '<mujoco><worldbody><body name="b"><joint ref="90"/></body></worldbody></mujoco>'
        >>> body_joints(ET.fromstring(text), Path("robot.xml"))["b"][0].ref  # degrees by default
        1.5707963267948966

    """
    degrees = _angle_unit(root) != "radian"
    joints: dict[str, list[MjcfJoint]] = {}
    for body, joint, attributes in resolved(root, path, "joint"):
        name = body.get("name")
        slide = attributes.get("type", "hinge") == "slide"
        ref = float(attributes.get("ref", "0"))
        if not slide and degrees:
            ref = math.radians(ref)
        if name is None:
            if ref:
                raise ConfigError(f"{path}: a body with a joint whose ref is not 0 has no name; name it")
            continue
        own = joints.setdefault(name, [])
        values = attributes.get("range", "").split()
        span = (float(values[0]), float(values[1])) if slide and len(values) == 2 else None
        own.append(MjcfJoint(joint.get("name") or f"{name}_joint{len(own)}", ref, span))
    return joints


def _angle_unit(root: ET.Element) -> str:
    """The compiler's angle unit (MuJoCo's default: degree); the last ``<compiler>`` that gives one."""
    unit = "degree"
    for compiler in root.findall("compiler"):
        unit = compiler.get("angle", unit)
    return unit
