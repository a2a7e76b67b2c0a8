"""A calibrated URDF as offsets of the nominal one, in the forms robot stacks take.

Many stacks keep their vendor's URDF and take a calibration as numbers per joint (some
description packages take six per joint: ``<joint>_x_offset`` ...). For every
joint whose origin the calibration moved, ``offsets.yaml`` gives:

* ``angle_offset_rad`` (revolute and continuous joints): what the joint's driver adds to
  its encoder reading, ``q_model = q_encoder + angle_offset_rad``: the part of the
  origin's change that is a rotation about the joint's own axis (its twist);
* ``placement``: the rest of the change, ``x_m, y_m, z_m, roll_rad, pitch_rad, yaw_rad``,
  applied after the nominal origin: ``origin = nominal_origin * Trans(x, y, z) *
  RPY(roll, pitch, yaw)`` (URDF's fixed-axis roll-pitch-yaw).

The nominal URDF with every placement applied, and the angle offsets added to the
encoders, is the calibrated URDF (:func:`apply_offsets`, tested to 1e-9). Where the
calibrated URDF inserts a fixed joint below a moving one (a sole or gripper that is a
moving joint's own link), the entry says ``inserted: {parent, child}``: the moving joint
ends at the new empty link ``parent``, and the fixed joint's origin is ``placement``.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from posegen.errors import InputError
from posegen.io import dump_yaml, read_yaml, write_atomic
from posegen.numeric import is_finite_number
from posegen.robot import FloatArray

OFFSETS_FORMAT = "posegen-offsets"
OFFSETS_FILE = "offsets.yaml"
ROTATING = ("revolute", "continuous")
UNCHANGED = 1e-15  # m or rad: a joint whose change is below this in every number is left out
CONVENTION = (
    "per joint: angle_offset_rad is added by the joint's driver to its encoder reading (q_model = q_encoder + "
    "angle_offset_rad); placement is applied after the nominal joint origin: origin = nominal_origin * "
    "Trans(x_m, y_m, z_m) * RPY(roll_rad, pitch_rad, yaw_rad) (URDF fixed-axis roll, pitch, yaw); joints not "
    "listed are unchanged"
)
PLACEMENT_FIELDS = ("x_m", "y_m", "z_m", "roll_rad", "pitch_rad", "yaw_rad")
MAX_LENGTH_M = 10.0  # largest |x|, |y|, |z| of a placement change (a calibration moves joints by mm)
MAX_ANGLE_RAD = 2.0 * np.pi  # largest |angle| of an offset or a placement change


@dataclass(frozen=True)
class JointOffset:
    """How the calibration moved one joint."""

    joint: str
    angle_offset_rad: float  # 0 for a fixed or prismatic joint
    placement: tuple[float, float, float, float, float, float]  # x, y, z m; roll, pitch, yaw rad
    inserted: tuple[str, str] | None = None  # a fixed joint the calibration adds: (new empty parent link, child link)


def _numbers(joint: ET.Element, element: str, key: str, default: str) -> FloatArray:
    """Three finite numbers of a joint's ``<element key="...">`` (``default`` if absent).

    Raises:
        InputError: Not three finite numbers (the joint and the attribute named).

    """
    found = joint.find(element)
    text = default if found is None else found.get(key, default)
    try:
        values = np.array([float(v) for v in text.split()])
    except ValueError:
        values = np.array([])
    if values.shape != (3,) or not np.all(np.isfinite(values)):
        raise InputError(f'joint {joint.get("name")}: <{element} {key}="{text}">: expected three finite numbers')
    return values


def _origin(joint: ET.Element) -> FloatArray:
    """The joint's origin as a (4, 4) transform."""
    out = np.eye(4)
    out[:3, :3] = pin.rpy.rpyToMatrix(_numbers(joint, "origin", "rpy", "0 0 0"))
    out[:3, 3] = _numbers(joint, "origin", "xyz", "0 0 0")
    return out


def _axis(joint: ET.Element) -> FloatArray:
    vector = _numbers(joint, "axis", "xyz", "1 0 0")
    norm = float(np.linalg.norm(vector))
    if not norm > 0.0:
        raise InputError(f"joint {joint.get('name')}: its axis is 0 0 0 (a joint turns about a direction)")
    return np.asarray(vector / norm)


def _root(urdf_text: str, name: str) -> ET.Element:
    """The root element of a URDF's text.

    Raises:
        InputError: Not text, not XML, or not a ``<robot>``.

    """
    if not isinstance(urdf_text, str):
        raise InputError(f"{name}: expected the URDF's text, not {type(urdf_text).__name__}")
    try:
        root = ET.fromstring(urdf_text)
    except ET.ParseError as exc:
        raise InputError(f"{name}: not a URDF (not valid XML: {exc})") from None
    if root.tag != "robot":
        raise InputError(f"{name}: not a URDF (its root element is <{root.tag}>, not <robot>)")
    return root


def _joints(urdf_text: str, name: str) -> dict[str, ET.Element]:
    return {str(j.get("name")): j for j in _root(urdf_text, name).findall("joint")}


def _twist(rotation: FloatArray, axis: FloatArray) -> float:
    """Angle (rad) of the rotation's twist about ``axis`` (swing-twist decomposition)."""
    quaternion = pin.Quaternion(rotation)
    along = float(np.dot([quaternion.x, quaternion.y, quaternion.z], axis))
    angle = 2.0 * np.arctan2(along, quaternion.w)
    return float((angle + np.pi) % (2.0 * np.pi) - np.pi)


def joint_offsets(nominal_urdf: str, calibrated_urdf: str) -> list[JointOffset]:
    """Every joint the calibration moved, as an angle offset and a placement change.

    Args:
        nominal_urdf: The nominal URDF's text.
        calibrated_urdf: The calibrated URDF's text (the same joints).

    Raises:
        InputError: The two URDFs do not have the same joints (the differing ones named).

    Example:
        >>> offsets = joint_offsets(Path("robot.urdf").read_text(), Path("calibrated.urdf").read_text())

    """
    nominal = _joints(nominal_urdf, "the nominal URDF")
    calibrated = _joints(calibrated_urdf, "the calibrated URDF")
    added = [calibrated[n] for n in calibrated if n not in nominal]
    if set(nominal) - set(calibrated) or any(j.get("type") != "fixed" for j in added):
        differ = sorted(
            (set(nominal) - set(calibrated)) | {str(j.get("name")) for j in added if j.get("type") != "fixed"}
        )
        raise InputError(f"the calibrated URDF does not have the nominal URDF's joints: {', '.join(differ)}")
    out = [_inserted(joint) for joint in added]
    for name, joint in nominal.items():
        change = np.linalg.inv(_origin(joint)) @ _origin(calibrated[name])
        angle = 0.0
        if joint.get("type") in ROTATING:
            angle = _twist(change[:3, :3], _axis(joint))
            change[:3, :3] = change[:3, :3] @ pin.AngleAxis(-angle, _axis(joint)).matrix()
        placement = np.concatenate([change[:3, 3], pin.rpy.matrixToRpy(change[:3, :3])])
        if abs(angle) > UNCHANGED or np.max(np.abs(placement)) > UNCHANGED:
            out.append(JointOffset(name, angle, tuple(float(v) for v in placement)))  # type: ignore[arg-type]
    return out


def _inserted(joint: ET.Element) -> JointOffset:
    """A fixed joint the calibration inserted below a moving joint: its origin is the whole change."""
    parent, child = joint.find("parent"), joint.find("child")
    if parent is None or child is None:
        raise InputError(f"the calibrated URDF's joint {joint.get('name')} has no parent or child link")
    origin = _origin(joint)
    placement = np.concatenate([origin[:3, 3], pin.rpy.matrixToRpy(origin[:3, :3])])
    names = (str(parent.get("link")), str(child.get("link")))
    return JointOffset(str(joint.get("name")), 0.0, tuple(float(v) for v in placement), names)  # type: ignore[arg-type]


def _insert(root: ET.Element, offset: JointOffset) -> None:
    """Insert a calibration's fixed joint: the moving joint above ``child`` now ends at the new empty link."""
    assert offset.inserted is not None
    mount, child = offset.inserted
    above = [j for j in root.findall("joint") if (c := j.find("child")) is not None and c.get("link") == child]
    if len(above) != 1:
        raise InputError(f"offsets: joint {offset.joint} is inserted above link {child}, which no single joint ends at")
    above_child = above[0].find("child")
    assert above_child is not None
    above_child.set("link", mount)
    ET.SubElement(root, "link", {"name": mount})
    joint = ET.SubElement(root, "joint", {"name": offset.joint, "type": "fixed"})
    ET.SubElement(joint, "parent", {"link": mount})
    ET.SubElement(joint, "child", {"link": child})
    ET.SubElement(joint, "origin", {"xyz": "0 0 0", "rpy": "0 0 0"})


def apply_offsets(nominal_urdf: str, offsets: list[JointOffset]) -> str:
    """The nominal URDF with every placement change applied (the angle offsets stay with the encoders).

    Raises:
        InputError: ``nominal_urdf`` is not a URDF (its joints' origins and axes finite), an
            offset is not a :class:`JointOffset` within :data:`MAX_LENGTH_M` and
            :data:`MAX_ANGLE_RAD`, names a joint the URDF does not have, or gives an angle
            offset to a joint that does not rotate.

    Example:
        >>> text = apply_offsets(Path("robot.urdf").read_text(), read_offsets("offsets.yaml"))

    """
    root = _root(nominal_urdf, "nominal_urdf")
    if not isinstance(offsets, (list, tuple)):
        raise InputError(f"offsets: expected a list of JointOffset (read_offsets), not {type(offsets).__name__}")
    for offset in offsets:
        _check_offset(offset)
    for offset in offsets:
        if offset.inserted is not None:
            _insert(root, offset)
    joints = {str(j.get("name")): j for j in root.findall("joint")}
    unknown = sorted(o.joint for o in offsets if o.joint not in joints)
    if unknown:
        raise InputError(f"offsets of joints the URDF does not have: {', '.join(unknown)}")
    for offset in offsets:
        joint = joints[offset.joint]
        if offset.angle_offset_rad and joint.get("type") not in ROTATING:
            raise InputError(f"joint {offset.joint}: an angle offset, but the joint is {joint.get('type')}")
        change = np.eye(4)
        change[:3, :3] = pin.rpy.rpyToMatrix(np.array(offset.placement[3:]))
        change[:3, 3] = offset.placement[:3]
        moved = _origin(joint) @ change
        if not np.all(np.isfinite(moved)) or np.abs(moved[:3, 3]).max() > MAX_LENGTH_M:
            raise InputError(f"joint {offset.joint}: its calibrated origin {moved[:3, 3]} m is not a placement")
        origin = joint.find("origin")
        if origin is None:
            origin = ET.SubElement(joint, "origin")
        origin.set("xyz", " ".join(f"{v:.17g}" for v in moved[:3, 3]))
        origin.set("rpy", " ".join(f"{v:.17g}" for v in pin.rpy.matrixToRpy(moved[:3, :3])))
    return ET.tostring(root, encoding="unicode", xml_declaration=True)


def _check_offset(offset: JointOffset) -> None:
    """An offset's numbers: finite, lengths within :data:`MAX_LENGTH_M`, angles within :data:`MAX_ANGLE_RAD`.

    Raises:
        InputError: Not a :class:`JointOffset`, or a number out of range (the joint named).

    """
    if not isinstance(offset, JointOffset):
        raise InputError(f"offsets: expected JointOffset entries (read_offsets), not {type(offset).__name__}")
    problem = _offset_problem(offset.angle_offset_rad, offset.placement)
    if problem:
        raise InputError(f"offsets: joint {offset.joint}: {problem}")


def _offset_problem(angle: object, placement: object) -> str:
    """What is wrong with an offset's numbers ("" if nothing)."""
    values = list(placement) if isinstance(placement, (tuple, list)) else []
    if len(values) != len(PLACEMENT_FIELDS) or not all(is_finite_number(v) for v in [angle, *values]):
        return f"angle_offset_rad and placement ({', '.join(PLACEMENT_FIELDS)}) must be finite numbers"
    lengths, angles = values[:3], [angle, *values[3:]]
    if max(abs(v) for v in lengths) > MAX_LENGTH_M or max(abs(v) for v in angles) > MAX_ANGLE_RAD:
        return f"lengths must be within {MAX_LENGTH_M:g} m and angles within {MAX_ANGLE_RAD:.4g} rad"
    return ""


def offsets_data(offsets: list[JointOffset], urdf: str, nominal: str, provenance: dict[str, Any]) -> dict[str, Any]:
    """The content of ``offsets.yaml``."""
    return {
        "format": OFFSETS_FORMAT,
        "format_version": 1,
        "urdf": urdf,
        "nominal_urdf": nominal,
        "convention": CONVENTION,
        "joints": {
            o.joint: {
                "angle_offset_rad": float(o.angle_offset_rad),
                "placement": dict(zip(PLACEMENT_FIELDS, (float(v) for v in o.placement), strict=True)),
                **({"inserted": {"parent": o.inserted[0], "child": o.inserted[1]}} if o.inserted else {}),
            }
            for o in offsets
        },
        "provenance": provenance,
    }


def write_offsets(path: Path, offsets: list[JointOffset], urdf: str, nominal: str, provenance: dict[str, Any]) -> None:
    """Write ``offsets.yaml`` (atomically): ``urdf`` names the calibrated URDF beside it, ``nominal`` the vendor's."""
    write_atomic(path, dump_yaml(offsets_data(offsets, urdf, nominal, provenance)))


def read_offsets(path: str | Path, joint_names: tuple[str, ...] | None = None) -> list[JointOffset]:
    """Read and check an ``offsets.yaml``; with ``joint_names`` (the URDF's joints), every joint must be one of them.

    Raises:
        InputError: Not an offsets file, a value that is not a finite number (or a length
            past :data:`MAX_LENGTH_M`, an angle past :data:`MAX_ANGLE_RAD`), or joints that
            ``joint_names`` lacks (all of them named).

    Example:
        >>> offsets = read_offsets("plans/calibration/offsets.yaml")

    """
    data = read_yaml(path, OFFSETS_FORMAT)
    joints = data.get("joints")
    if not isinstance(joints, dict):
        raise InputError(f"{path}: 'joints' must be a mapping of joint names")
    out = []
    for name, entry in joints.items():
        placement = entry.get("placement") if isinstance(entry, dict) else None
        angle = entry.get("angle_offset_rad") if isinstance(entry, dict) else None
        values = [placement.get(f) for f in PLACEMENT_FIELDS] if isinstance(placement, dict) else [None]
        problem = _offset_problem(angle, values)
        if problem:
            raise InputError(f"{path}: joints.{name}: {problem}")
        inserted = entry.get("inserted")
        links = (inserted.get("parent"), inserted.get("child")) if isinstance(inserted, dict) else None
        if inserted is not None and (links is None or not all(isinstance(v, str) and v for v in links)):
            raise InputError(f"{path}: joints.{name}.inserted: expected 'parent' and 'child' link names")
        values_tuple = tuple(float(v) for v in values if v is not None)
        out.append(JointOffset(str(name), float(angle), values_tuple, links))  # type: ignore[arg-type]
    if joint_names is not None:
        unknown = sorted(o.joint for o in out if o.joint not in joint_names and o.inserted is None)
        if unknown:
            raise InputError(f"{path}: offsets of joints the URDF does not have: {', '.join(unknown)}")
    return out
