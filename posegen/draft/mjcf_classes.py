"""An MJCF element's attributes as MuJoCo resolves them through the default classes.

An attribute a ``<joint>`` or ``<geom>`` does not give comes from its class's defaults:
its ``class``, else the ``childclass`` of the nearest body around it (its own included),
else ``main``; a class's defaults are its element's attributes over those of the classes
it is nested in (:func:`resolved`).

pinocchio's MJCF parser reads classes otherwise: it skips a ``pos`` that comes from a class
(a joint's axis or a geom turned about the wrong point), and lays the enclosing body's
``childclass`` over an element's own ``class``. :func:`write_resolved` writes the
attributes the conversion depends on onto each element, so that pinocchio reads them as
MuJoCo does.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path

from posegen.errors import ConfigError

MAIN_CLASS = "main"
# the attributes written on each element: MuJoCo's own default, or None (written only when a class gives it)
WRITTEN: dict[str, dict[str, str | None]] = {
    "joint": {"type": "hinge", "axis": "0 0 1", "pos": "0 0 0", "ref": "0", "range": None},
    "geom": {
        "type": "sphere", "contype": "1", "conaffinity": "1", "group": "0", "pos": "0 0 0", "quat": "1 0 0 0",
        "size": None, "fromto": None, "mesh": None, "mass": None, "density": None,
    },
}  # fmt: skip


def class_defaults(root: ET.Element, tag: str) -> dict[str, dict[str, str]]:
    """Each default class's attributes for ``tag`` elements, those of the classes it is nested in included.

    Example:
        >>> leg = '<default class="leg"><joint axis="0 1 0"/></default>'
        >>> class_defaults(ET.fromstring(f'<mujoco><default><joint ref="1"/>{leg}</default></mujoco>'), "joint")["leg"]
        {'ref': '1', 'axis': '0 1 0'}

    """
    classes: dict[str, dict[str, str]] = {}

    def visit(element: ET.Element, inherited: dict[str, str]) -> None:
        own = dict(inherited)
        for child in element.findall(tag):
            own.update(child.attrib)
        classes[element.get("class", MAIN_CLASS)] = own
        for child in element.findall("default"):
            visit(child, own)

    for top in root.findall("default"):
        visit(top, {})
    return classes


def resolved(root: ET.Element, path: Path, tag: str) -> Iterator[tuple[ET.Element, ET.Element, dict[str, str]]]:
    """Each body's ``tag`` elements, in document order, with their attributes over their class's defaults.

    Args:
        root: The flattened MJCF (includes inlined, frames made bodies).
        path: The MJCF file, named in errors.
        tag: ``"joint"`` or ``"geom"``.

    Yields:
        The body, the element, and its resolved attributes.

    Raises:
        ConfigError: An element names a class no default defines.

    Example:
        >>> text = '<mujoco><worldbody><body><joint axis="1 0 0"/></body></worldbody></mujoco>'
        >>> [a for _, _, a in resolved(ET.fromstring(text), Path("robot.xml"), "joint")]
        [{'axis': '1 0 0'}]

    """
    classes = class_defaults(root, tag)

    def visit(body: ET.Element, childclass: str) -> Iterator[tuple[ET.Element, ET.Element, dict[str, str]]]:
        childclass = body.get("childclass", childclass)
        for element in body.findall(tag):
            kind = element.get("class", childclass)
            if kind not in classes and kind != MAIN_CLASS:
                raise ConfigError(f"{path}: {tag} class '{kind}' has no <default class=\"{kind}\">")
            yield body, element, {**classes.get(kind, {}), **element.attrib}
        for child in body.findall("body"):
            yield from visit(child, childclass)

    for world in root.findall("worldbody"):
        for body in world.findall("body"):
            yield from visit(body, MAIN_CLASS)


def write_resolved(root: ET.Element, path: Path) -> None:
    """Write the attributes of :data:`WRITTEN` on each joint and geom, as MuJoCo resolves them.

    An attribute no class gives is written as MuJoCo's own default where it has one here
    (so that no ``childclass`` of pinocchio's reading replaces it); a geom placed by its
    ``fromto`` gets no ``pos``, and one turned by another orientation attribute no ``quat``.

    Raises:
        ConfigError: An element names a class no default defines.

    Example:
        >>> body = "<worldbody><body><joint/></body></worldbody>"
        >>> root = ET.fromstring(f'<mujoco><default><joint pos="0 0 1"/></default>{body}</mujoco>')
        >>> write_resolved(root, Path("robot.xml"))
        >>> root.find(".//body/joint").get("pos"), root.find(".//body/joint").get("axis")
        ('0 0 1', '0 0 1')

    """
    turned = ("axisangle", "euler", "xyaxes", "zaxis", "fromto")
    for tag, keys in WRITTEN.items():
        for _, element, attributes in list(resolved(root, path, tag)):
            if tag == "joint" and attributes.get("type", "hinge") not in ("hinge", "slide"):
                continue  # a ball or free joint, as written (refused with its name once read)
            for key, built_in in keys.items():
                placed = key == "pos" and element.get("fromto") is not None
                if placed or (key == "quat" and any(element.get(t) is not None for t in turned)):
                    continue
                value = attributes.get(key, built_in)
                if value is not None:
                    element.set(key, value)
