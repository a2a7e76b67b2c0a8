"""The scalar parameters of the calibration model: what each one is, its unit and its name.

A parameter is a field of a robot placement (px, py, pz in m; phix, phiy, phiz in rad,
URDF rpy), of a chain's flush contact frame (z in m; roll, pitch in rad), of a chain's
contact point (x, y, z in m, in its point frame) or of a table session's plane (z, roll,
pitch). Its name, the text artefacts and users see, is made here and nowhere else:
``<placement>.<field>``, ``<contact frame>.<field>``, ``<point frame>.<field>`` and
``plane@<session>.<field>``.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

PLACEMENT_FIELDS = ("px", "py", "pz", "phix", "phiy", "phiz")
OFFSET_FIELDS = ("z", "roll", "pitch")  # a contact frame's or a plane's offset
POINT_FIELDS = ("x", "y", "z")  # a contact point's position in its point frame


class Unit(str, enum.Enum):
    """Physical unit of a parameter."""

    LENGTH = "m"
    ANGLE = "rad"


class Group(str, enum.Enum):
    """What a parameter describes."""

    PLACEMENT = "placement"  # a joint or frame placement of the robot
    CONTACT = "contact"  # the flush contact frame in the gripper frame
    POINT = "point"  # the contact point in its point frame
    PLANE = "plane"  # the table plane of a session, in the sole frame


@dataclass(frozen=True)
class Parameter:
    """One scalar parameter of the model, identified by its group, owner and field."""

    group: Group
    owner: str  # the placement (joint or frame), the contact frame, or the table session
    field: str  # one of PLACEMENT_FIELDS, of OFFSET_FIELDS (contacts, planes) or of POINT_FIELDS

    @classmethod
    def placement(cls, name: str, field: str) -> Parameter:
        """A field of the placement of joint or frame ``name``."""
        return cls(Group.PLACEMENT, name, field)

    @classmethod
    def contact(cls, frame: str, field: str) -> Parameter:
        """A field of the offset of contact frame ``frame``."""
        return cls(Group.CONTACT, frame, field)

    @classmethod
    def point(cls, frame: str, field: str) -> Parameter:
        """A coordinate of the contact point of point frame ``frame``."""
        return cls(Group.POINT, frame, field)

    @classmethod
    def plane(cls, session: str, field: str) -> Parameter:
        """A field of the table plane of ``session``."""
        return cls(Group.PLANE, session, field)

    @property
    def unit(self) -> Unit:
        """M for translations, offset heights and point coordinates, rad for angles."""
        length = {Group.PLACEMENT: ("px", "py", "pz"), Group.POINT: POINT_FIELDS}.get(self.group, ("z",))
        return Unit.LENGTH if self.field in length else Unit.ANGLE

    @property
    def name(self) -> str:
        """The text that names the parameter in artefacts."""
        if self.group == Group.PLANE:
            return f"plane@{self.owner}.{self.field}"
        return f"{self.owner}.{self.field}"

    def __str__(self) -> str:
        return self.name
