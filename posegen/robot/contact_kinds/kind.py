"""A contact kind: how a hand touches the table, as one object.

Everything posegen does differently for a kind of contact is a method or an attribute
of its object: which config fields declare it, the frame it constrains, how ``pool``
plans it (lift above the table, orientation held or free) and judges a planned posture,
its contact parameters and the gripper-to-tip transform they make, what it measures
(which of the (height, roll, pitch) rows are real) with the Jacobian of that measure,
and how the calibrated URDF carries it. The code that uses kinds never names one: it
asks the kind. The kinds are listed in :mod:`posegen.robot.contact_kinds` (adding one
is a module beside this one plus a line there).

The objects are pure geometry (numpy, pinocchio) at the robot layer, so that config
reading and planning (robot) and the measurement model (model) share one object;
parameters are named by the model from the kind's ``group`` and ``fields``.
"""

from __future__ import annotations

import abc
from typing import TYPE_CHECKING, ClassVar

import numpy as np
import pinocchio as pin

from posegen.robot.geometry import FloatArray

if TYPE_CHECKING:
    from posegen.robot.chain_config import ChainConfig
    from posegen.robot.feasibility import Assessment
    from posegen.robot.scene import Scene


class ContactKind(abc.ABC):
    """How a hand touches the table (one subclass, and one instance, per kind).

    Kinds compare, hash and sort by ``value`` (their name in configs and artefacts).
    Every contact keeps the (height, roll, pitch) layout of residuals (n, 3) and
    Jacobians (n, 3, p); a kind that measures fewer rows leaves the others zero.
    """

    value: ClassVar[str]  # name in configs and artefacts ("flush", "point")
    frame_title: ClassVar[str]  # what its frame is called in messages ("contact frame")
    required_field: ClassVar[str]  # the chain config field that declares it
    group: ClassVar[str]  # posegen.model.Group value of its contact parameters
    fields: ClassVar[tuple[str, ...]]  # its contact parameters (m or rad), in order
    rows: ClassVar[tuple[bool, bool, bool]]  # which of (height, roll, pitch) it measures
    aligned: ClassVar[bool]  # pool holds the frame's z along the table normal (else: within a cone)
    folded: ClassVar[bool]  # URDF: its offsets fold into the gripper frame (its frame is derived at load)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ContactKind) and other.value == self.value

    def __hash__(self) -> int:
        return hash(self.value)

    def __lt__(self, other: ContactKind) -> bool:
        return self.value < other.value

    def __repr__(self) -> str:
        return f"<contact kind {self.value}>"

    # config

    @abc.abstractmethod
    def declared(self, chain: ChainConfig) -> bool:
        """Whether the chain's config declares a contact of this kind."""

    @abc.abstractmethod
    def check(self, chain: ChainConfig, planned: bool) -> None:
        """Check the chain's fields of this kind (``planned``: its ``contact_kind``).

        Raises:
            ConfigError: A field is missing or out of range (named).

        """

    @abc.abstractmethod
    def frame(self, chain: ChainConfig) -> str:
        """The frame whose pose a contact of this kind constrains."""

    @abc.abstractmethod
    def carried_frames(self, chain: ChainConfig) -> tuple[str, ...]:
        """The frames on the gripper this kind reads (they touch the table, move with the gripper)."""

    # robot geometry

    @abc.abstractmethod
    def nominal_tip(self, scene: Scene, chain: ChainConfig) -> FloatArray | None:
        """The kind's frame in the gripper frame, nominal (4, 4); None when not declared."""

    @abc.abstractmethod
    def placement_in_gripper(self, model: pin.Model, data: pin.Data, chain: ChainConfig, q: FloatArray) -> FloatArray:
        """The kind's frame in the gripper frame of a loaded model, after frame kinematics at q. Shape (4, 4)."""

    # planning

    @abc.abstractmethod
    def lift_m(self, chain: ChainConfig) -> float:
        """Height of the kind's frame above the table at a contact (m)."""

    @abc.abstractmethod
    def excess(self, assessment: Assessment, height_tol_m: float, angle_tol_rad: float) -> float:
        """A planned posture's contact excess over its bounds (> 0: violated), m or rad."""

    @abc.abstractmethod
    def detail(self, assessment: Assessment) -> str:
        """A planned posture's contact figures, as a short text."""

    # measurement

    @abc.abstractmethod
    def tip_offset(self, params: FloatArray) -> FloatArray:
        """Offset of the tip from its nominal frame at contact parameters ``params`` (len(fields),). Shape (4, 4)."""

    @abc.abstractmethod
    def tip_offset_derivatives(self, params: FloatArray) -> FloatArray:
        """Derivatives of :meth:`tip_offset` w.r.t. each parameter. Shape (len(fields), 4, 4)."""

    @abc.abstractmethod
    def measure(self, frames: FloatArray, chain: ChainConfig) -> FloatArray:
        """Residuals (n, 3) of tip frames (n, 4, 4) in their plane frame; unmeasured rows zero."""

    @abc.abstractmethod
    def measure_jacobian(self, row: FloatArray, d_row: FloatArray) -> FloatArray:
        """Derivatives (n, 3, p) of :meth:`measure` given the frames' third rows (n, 4) and theirs (n, p, 4).

        Column by column: a parameter's derivatives depend on its own column of ``d_row``
        alone (callers measure the derivatives of several parameter sets in one call).
        """


def height_rows(d_row: FloatArray) -> FloatArray:
    """Derivatives (n, 3, p) of the rows (height, 0, 0) given the third row's (n, p, 4)."""
    out = np.zeros((d_row.shape[0], 3, d_row.shape[1]))
    out[:, 0] = d_row[:, :, 3]
    return out
