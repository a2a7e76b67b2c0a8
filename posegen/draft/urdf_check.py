"""A URDF read for what ``robot init`` needs before any parser sees it: one tree, finite numbers, some mass.

pinocchio's URDF parser (urdfdom) prints several lines of its own on a malformed file and
then fails with "not a valid URDF", or loads what it should not (a NaN origin, an axis
``0 0 0``, a robot of no mass) and the draft fails far later, naming another cause. So the
text is checked here first, and each defect is said in one line naming the file and the
element: a link or joint named twice or not at all, a joint's parent or child that is no
link, a link carried by two joints, a loop, links no joint connects to the root, a joint
type URDF does not have, a moving joint that is not one value between limits (continuous,
planar, floating) or whose lower limit is above its upper, an origin, axis, limit, mass,
inertia or shape size that is not finite numbers, an axis of zero length, a negative mass,
and a robot without mass.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

from posegen.errors import ConfigError

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
MOVING = ("revolute", "continuous", "prismatic", "planar")
INERTIA_NOISE = 1e-9  # kg m^2: a CAD export's -5e-20 (one of iCub's hips) is a zero, not a negative moment
MIN_AXIS_LENGTH = 1e-6  # a shorter axis is no direction (its square underflows, or a unit vector of noise)
UNBOUNDED = ("continuous", "planar", "floating")  # joints of no range, or of more than one value
_VECTORS = (  # (element path under a link or joint, attribute, how many numbers, what they are)
    ("origin", "xyz", 3),
    ("origin", "rpy", 3),
    ("axis", "xyz", 3),
    ("inertial/origin", "xyz", 3),
    ("inertial/origin", "rpy", 3),
    ("visual/origin", "xyz", 3),
    ("visual/origin", "rpy", 3),
    ("collision/origin", "xyz", 3),
    ("collision/origin", "rpy", 3),
    ("visual/geometry/box", "size", 3),
    ("collision/geometry/box", "size", 3),
    ("visual/geometry/mesh", "scale", 3),
    ("collision/geometry/mesh", "scale", 3),
)
_SCALARS = (
    ("limit", ("lower", "upper", "effort", "velocity")),
    ("inertial/mass", ("value",)),
    ("inertial/inertia", ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")),
    ("visual/geometry/cylinder", ("radius", "length")),
    ("collision/geometry/cylinder", ("radius", "length")),
    ("visual/geometry/sphere", ("radius",)),
    ("collision/geometry/sphere", ("radius",)),
)


def check_urdf(text: str, where: str | Path) -> None:
    """Check a URDF's text before pinocchio reads it.

    Args:
        text: The URDF.
        where: The file, named in errors.

    Raises:
        ConfigError: The first defect found (see the module's docstring), naming ``where``
            and the element.

    Example:
        >>> check_urdf(Path("robot.urdf").read_text(), "robot.urdf")  # doctest: +SKIP

    """
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise ConfigError(f"{where}: not valid XML ({exc})") from exc
    if root.tag != "robot":
        raise ConfigError(f"{where}: not a URDF (its root element is <{root.tag}>, not <robot>)")
    links = _names(root, "link", where)
    joints = root.findall("joint")
    _names(root, "joint", where)
    for element in [*root.findall("link"), *joints]:
        _check_numbers(element, where)
    parent_of = _tree(joints, links, where)
    _check_connected(links, parent_of, where)
    masses = [_number(m, "value") for m in root.findall("link/inertial/mass")]
    if not any(m > 0.0 for m in masses):
        raise ConfigError(
            f"{where}: every link has zero mass (or none): posegen needs the masses (balance, holding torques); "
            "give each link its <inertial><mass>"
        )


def _names(root: ET.Element, tag: str, where: str | Path) -> list[str]:
    """The names of the ``tag`` elements, each given once."""
    names = [str(e.get("name", "")) for e in root.findall(tag)]
    for name in names:
        if not name.strip():
            raise ConfigError(f"{where}: a <{tag}> without a name")
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ConfigError(f"{where}: {tag} '{twice[0]}' is defined twice")
    return names


def _label(element: ET.Element) -> str:
    return f"{element.tag} '{element.get('name')}'"


def _number(element: ET.Element, key: str) -> float:
    return number(element.get(key, "0"))


def number(text: str | None) -> float:
    """An XML attribute's number; nan when it is none (the URDF and MJCF checks' reading)."""
    try:
        return float(str(text))
    except ValueError:
        return math.nan


def numbers(text: str) -> list[float]:
    """An XML attribute's list of numbers; empty when one is not a number."""
    try:
        return [float(v) for v in text.split()]
    except ValueError:
        return []


def _check_numbers(element: ET.Element, where: str | Path) -> None:
    """Every number of a link or joint finite; a moving joint's axis not of zero length; no negative mass."""
    for path, key, count in _VECTORS:
        for found in element.findall(path):
            text = found.get(key)
            if text is None:
                continue
            values = numbers(text)
            if len(values) != count or not all(math.isfinite(v) for v in values):
                raise ConfigError(
                    f'{where}: {_label(element)}: <{path} {key}="{text}">: expected {count} finite numbers'
                )
    for path, keys in _SCALARS:
        for found in element.findall(path):
            for key in keys:
                if found.get(key) is not None and not math.isfinite(_number(found, key)):
                    raise ConfigError(
                        f'{where}: {_label(element)}: <{path} {key}="{found.get(key)}">: expected a finite number'
                    )
    for kind in ("visual", "collision"):
        for mesh in element.findall(f"{kind}/geometry/mesh"):
            if 0.0 in numbers(mesh.get("scale", "1 1 1")):
                scale = mesh.get("scale")
                raise ConfigError(f'{where}: {_label(element)}: <mesh scale="{scale}">: a mesh scaled to nothing')
    for mass in element.findall("inertial/mass"):
        if _number(mass, "value") < 0.0:
            raise ConfigError(f"{where}: {_label(element)}: a negative mass ({mass.get('value')} kg)")
    for inertia in element.findall("inertial/inertia"):
        for key in ("ixx", "iyy", "izz"):
            if inertia.get(key) is not None and _number(inertia, key) < -INERTIA_NOISE:
                raise ConfigError(
                    f'{where}: {_label(element)}: <inertia {key}="{inertia.get(key)}">: a moment of inertia '
                    "cannot be negative (kg m^2)"
                )
    axis = element.find("axis")
    moving = element.tag == "joint" and element.get("type") in MOVING
    direction = [float(v) for v in axis.get("xyz", "1 0 0").split()] if axis is not None else [1.0]
    if moving and math.sqrt(sum(v * v for v in direction)) < MIN_AXIS_LENGTH:
        raise ConfigError(
            f"{where}: {_label(element)}: its axis is {axis.get('xyz') if axis is not None else ''}, of no length "
            "(a joint moves along a direction)"
        )


def _tree(joints: list[ET.Element], links: list[str], where: str | Path) -> dict[str, str]:
    """Each link's parent link, from the joints (checked: known types, parents and children that are links)."""
    known = set(links)
    parent_of: dict[str, str] = {}
    for joint in joints:
        kind = joint.get("type")
        if kind not in JOINT_TYPES:
            raise ConfigError(
                f"{where}: {_label(joint)}: type {kind!r} is not a URDF joint type ({', '.join(JOINT_TYPES)})"
            )
        _check_motion(joint, where)
        ends = {}
        for end in ("parent", "child"):
            found = joint.find(end)
            name = None if found is None else found.get("link")
            if name is None:
                raise ConfigError(f"{where}: {_label(joint)}: no <{end} link=...>")
            if name not in known:
                raise ConfigError(f"{where}: {_label(joint)}: its {end} link '{name}' is not a link of the URDF")
            ends[end] = name
        child = ends["child"]
        if child in parent_of:
            raise ConfigError(
                f"{where}: link '{child}' is the child of two joints (a URDF is a tree; a closed chain is not)"
            )
        parent_of[child] = ends["parent"]
    return parent_of


def _check_motion(joint: ET.Element, where: str | Path) -> None:
    """A moving joint is one angle or length between limits (revolute or prismatic), its lower limit below its upper."""
    kind = joint.get("type")
    if kind in UNBOUNDED:
        raise ConfigError(
            f"{where}: {_label(joint)} is {kind}: posegen plans joints of one angle or length between limits; "
            "make it revolute (or fixed) with <limit lower=... upper=...> (MJCF: a hinge with a range)"
        )
    limit = joint.find("limit")
    if kind in ("revolute", "prismatic") and limit is not None:
        lower, upper = _number(limit, "lower"), _number(limit, "upper")
        if lower > upper:
            raise ConfigError(
                f'{where}: {_label(joint)}: <limit lower="{limit.get("lower")}" upper="{limit.get("upper")}">: '
                "its lower limit is above its upper"
            )


def _check_connected(links: list[str], parent_of: dict[str, str], where: str | Path) -> None:
    """One root link, every link below it, no loop."""
    for link in links:
        seen = {link}
        at = link
        while at in parent_of:
            at = parent_of[at]
            if at in seen:
                raise ConfigError(f"{where}: the joints form a loop through link '{link}' (a URDF is a tree)")
            seen.add(at)
    roots = [link for link in links if link not in parent_of]
    if len(roots) != 1:
        shown = ", ".join(f"'{r}'" for r in roots[:4])
        raise ConfigError(f"{where}: {len(roots)} root links ({shown}): no joint connects them; a URDF is one tree")
