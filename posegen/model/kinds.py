"""Parameter kinds: the physical directions a prior is put on, over the whole parameter vector.

Placements are stored as URDF xyz rpy, but manufacturing tolerances are stated per
physical kind: a link translation (m, in the parent frame), a joint offset (the encoder
zero: a rotation about the joint axis), an axis tilt (a rotation perpendicular to the
axis: bearing seats), the rotation of a fixed frame (a sole or the gripper's mount),
the contact frame's height and tilt in the gripper frame, a contact point's position in
its point frame, and a joint compliance
(rad/N m). Each placement's rpy deviation is mapped to the rotation it makes in the
joint's own frame, split along these directions. Table planes and the floor's
session constants have no prior (where the table and the feet are is not known).

The basis is a square, invertible matrix B over the calibration model's parameter
vector x: x = x_nominal + B delta, with delta the deviation along each direction. It is
exact for translations and first order for rotations (rpy is not linear), which is all
a Gaussian prior on millimetre and tenth-of-degree deviations needs.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from posegen.model.contact_model import ContactModel
from posegen.model.parameters import OFFSET_FIELDS, Group, Unit
from posegen.robot import FloatArray, rpy_derivatives, rpy_matrix


class Kind(str, enum.Enum):
    """What a direction of the parameter vector describes, and so which prior it gets."""

    JOINT_OFFSET = "joint_offset"  # rad, about a joint's axis
    AXIS_TILT = "axis_tilt"  # rad, perpendicular to a joint's axis
    LINK_TRANSLATION = "link_translation"  # m, a placement's xyz
    FRAME_ROTATION = "frame_rotation"  # rad, a fixed frame (sole, gripper mount)
    CONTACT_HEIGHT = "contact_height"  # m, contact frame along the gripper normal
    CONTACT_TILT = "contact_tilt"  # rad, contact frame roll and pitch
    CONTACT_POINT = "contact_point"  # m, a contact point's x, y, z in its point frame
    COMPLIANCE = "compliance"  # rad/N m, a joint's deflection under its gravity torque
    PLANE = "plane"  # a table session's plane: no prior
    FLOOR = "floor"  # a session's second-sole x, y, yaw: no prior


class Part(str, enum.Enum):
    """Where on the robot (or around it) a direction lies."""

    LEG = "leg"  # sole up to the root
    TORSO = "torso"  # shared by every chain
    ARM = "arm"  # one chain's own, down to the gripper mount
    CONTACT = "contact"  # the contact frame or point
    SCENE = "scene"  # planes, floor constants
    JOINT = "joint"  # compliance groups


@dataclass(frozen=True)
class Direction:
    """One direction of the kind basis."""

    kind: Kind
    part: Part
    owner: str  # placement, contact frame, session or compliance group
    label: str  # "tx", "offset", "tilt_1", "rz", "z", "roll", ...

    @property
    def name(self) -> str:
        """``<owner>.<label>``, as reports show it."""
        return f"{self.owner}.{self.label}"


def contact_prior(group: Group, unit: Unit) -> Kind:
    """The prior kind of a contact parameter: a frame offset's height or tilt, or a point's coordinate."""
    if group == Group.POINT:
        return Kind.CONTACT_POINT
    return Kind.CONTACT_HEIGHT if unit == Unit.LENGTH else Kind.CONTACT_TILT


def body_rates(phi: FloatArray) -> FloatArray:
    """Rotation, in the rotated frame, made by unit changes of URDF rpy (phix, phiy, phiz). Shape (3, 3) by column."""
    rotation = rpy_matrix(phi)
    columns = [rotation.T @ d for d in rpy_derivatives(phi)]  # skew-symmetric
    return np.column_stack([[c[2, 1], c[0, 2], c[1, 0]] for c in columns])


def _perpendicular(axis: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Two unit vectors completing ``axis`` to a right-handed frame."""
    axis = axis / np.linalg.norm(axis)
    helper = np.eye(3)[int(np.argmin(np.abs(axis)))]
    first = np.cross(axis, helper)
    first /= np.linalg.norm(first)
    return first, np.cross(axis, first)


def kind_basis(
    model: ContactModel,
    parts: dict[str, Part],
    compliance: Sequence[str],
    floor_sessions: Sequence[str],
) -> tuple[tuple[Direction, ...], FloatArray]:
    """Directions of the parameter vector [theta | compliance | floor constants] and its basis.

    Args:
        model: Contact model (theta's layout).
        parts: Placement name -> the part it belongs to.
        compliance: Names of the compliance groups (one parameter each, after theta).
        floor_sessions: Sessions whose floor constants (x, y, yaw) follow.

    Returns:
        The directions and B, shape (nx, nx), with x = x_nominal + B delta.

    """
    nx = model.size + len(compliance) + 3 * len(floor_sessions)
    columns: list[FloatArray] = []
    directions: list[Direction] = []

    def add(direction: Direction, entries: dict[int, float]) -> None:
        column = np.zeros(nx)
        for index, value in entries.items():
            column[index] = value
        columns.append(column)
        directions.append(direction)

    seen: set[str] = set()
    for chain in model.chains.values():
        for element in chain.elements:
            if element.name in seen:
                continue
            seen.add(element.name)
            part = parts[element.name]
            cols = model.placement_columns(element.name)
            for k, label in enumerate(("tx", "ty", "tz")):
                add(Direction(Kind.LINK_TRANSLATION, part, element.name, label), {cols[k]: 1.0})
            to_rpy = np.linalg.inv(body_rates(element.nominal[3:]))  # rotation in the joint frame -> d rpy
            if element.axis is None:
                rotations = [(Kind.FRAME_ROTATION, label, np.eye(3)[k]) for k, label in enumerate(("rx", "ry", "rz"))]
            else:
                first, second = _perpendicular(element.axis)
                rotations = [
                    (Kind.JOINT_OFFSET, "offset", element.axis),
                    (Kind.AXIS_TILT, "tilt_1", first),
                    (Kind.AXIS_TILT, "tilt_2", second),
                ]
            for kind, label, axis in rotations:
                rpy = to_rpy @ axis
                entries = {c: float(v) for c, v in zip(cols[3:], rpy, strict=True)}
                add(Direction(kind, part, element.name, label), entries)
    for name in model.chains:
        for contact_kind in model.kinds[name]:
            for col in model.tip_columns(name, contact_kind):
                p = model.parameters[col]
                add(Direction(contact_prior(p.group, p.unit), Part.CONTACT, p.owner, p.field), {col: 1.0})
    for session in model.sessions:
        for col, field in zip(model.plane_columns(session), OFFSET_FIELDS, strict=True):
            add(Direction(Kind.PLANE, Part.SCENE, session, field), {col: 1.0})
    for k, group in enumerate(compliance):
        add(Direction(Kind.COMPLIANCE, Part.JOINT, group, "compliance"), {model.size + k: 1.0})
    base = model.size + len(compliance)
    for s, session in enumerate(floor_sessions):
        for k, field in enumerate(("x", "y", "yaw")):
            add(Direction(Kind.FLOOR, Part.SCENE, f"floor@{session}", field), {base + 3 * s + k: 1.0})
    return tuple(directions), np.column_stack(columns)
