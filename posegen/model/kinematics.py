"""Parametric sole-to-contact kinematics of one chain, with its analytic Jacobian.

A chain is read from the scene's pinocchio model: the sole frame, the joints up to the
root (traversed against the URDF direction), the joints down to the gripper, the
gripper frame and the contact's tip: posegen's flush contact frame, or the chain's point
frame. Every placement carries the six URDF parameters (px, py, pz in m; phix, phiy, phiz
in rad, URDF rpy: R = Rz Ry Rx); a flush contact frame adds three (z, roll, pitch offsets
in the gripper frame), a contact point three (its x, y, z in the point frame), and each
table session a plane (z, roll, pitch in the sole frame).

The measurement of a flush contact is the contact frame's height, roll and pitch in the
plane frame, zero at every recorded contact; that of a point contact is the point's
height above the plane less the tip's radius (one number: the hand's orientation is free).

Everything is vectorised over postures: shapes ``(n, ...)`` with n postures.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError
from posegen.robot import (
    DEFAULT_KIND,
    ContactKind,
    FloatArray,
    Scene,
    placement_derivatives,
    placement_matrix,
    registered_kinds,
)


@dataclass(frozen=True)
class Element:
    """One placement of the chain, possibly followed by a revolute joint."""

    name: str  # joint or frame whose placement this is
    nominal: FloatArray  # (6,) URDF xyz rpy
    reverse: bool  # traversed against the URDF direction (sole up to the root)
    axis: FloatArray | None  # (3,) unit joint axis, None for a fixed placement
    joint: int | None  # index of the joint in Scene.joint_names


def _axis(joint: pin.JointModel) -> FloatArray:
    short = joint.shortname()
    for letter, axis in (("RX", 0), ("RY", 1), ("RZ", 2)):
        if short.endswith(letter):
            return np.eye(3)[axis]
    if "RevoluteUnaligned" in short:
        return np.array(joint.extract().axis, dtype=float)  # the generic JointModel hides the axis
    raise ConfigError(f"joint type {short} is not supported in a calibration chain (revolute joints only)")


def _xyz_rpy(placement: pin.SE3) -> FloatArray:
    return np.concatenate([placement.translation, pin.rpy.matrixToRpy(placement.rotation)])


class ChainModel:
    """Sole-to-contact kinematics of one chain.

    Attributes:
        chain: Chain name.
        config: The chain's config.
        elements: Placements from the sole to the gripper frame.
        placement_names: Names of the placements, in chain order.

    """

    def __init__(self, scene: Scene, chain: str, kinds: Sequence[ContactKind] = ()) -> None:
        """Read the chain from the scene; ``kinds``: contact kinds to know beyond the registered ones."""
        cfg = scene.chain(chain)
        model = scene.model
        self.chain = chain
        self.config = cfg
        sole = model.frames[scene.frame_id(cfg.sole_frame)]
        grip = model.frames[scene.frame_id(cfg.gripper_frame)]
        up = _ancestors(model, sole.parentJoint)  # sole joint .. first joint below the root
        down = _ancestors(model, grip.parentJoint)[::-1]  # first joint below the root .. gripper joint
        shared = set(up) & set(down)
        up = [j for j in up if j not in shared]
        down = [j for j in down if j not in shared]
        name_of = {model.getJointId(n): i for i, n in enumerate(scene.joint_names)}
        elements = [Element(cfg.sole_frame, _xyz_rpy(sole.placement), True, None, None)]
        for j in up:
            elements.append(
                Element(model.names[j], _xyz_rpy(model.jointPlacements[j]), True, _axis(model.joints[j]), name_of[j])
            )
        for j in down:
            elements.append(
                Element(model.names[j], _xyz_rpy(model.jointPlacements[j]), False, _axis(model.joints[j]), name_of[j])
            )
        elements.append(Element(cfg.gripper_frame, _xyz_rpy(grip.placement), False, None, None))
        self.elements = tuple(elements)
        known = dict.fromkeys((*registered_kinds(), *kinds))
        self._tips = {kind: kind.nominal_tip(scene, cfg) for kind in known}  # kind -> (4, 4) in the gripper, or None
        self.placement_names = tuple(e.name for e in elements)
        self._rotation_cache: dict[tuple[int, bytes], FloatArray] = {}

    @property
    def joint_indices(self) -> list[int]:
        """Indices (in Scene.joint_names) of the chain's joints, sole to gripper."""
        return [e.joint for e in self.elements if e.joint is not None]

    def frame(self, kind: ContactKind) -> str:
        """The frame a contact of this kind constrains (e.g. the flush contact frame, a point frame)."""
        return kind.frame(self.config)

    def tip_nominal(self, kind: ContactKind) -> FloatArray:
        """Nominal tip frame of a contact kind in the gripper frame. Shape (4, 4).

        Raises:
            ConfigError: The chain declares no contact of this kind.

        """
        tip = self._tips.get(kind)
        if tip is None:
            raise ConfigError(
                f"chains.{self.chain}.{kind.required_field}: missing (a {kind.value} contact of this chain needs it)"
            )
        return tip

    def tip(self, contact: FloatArray, kind: ContactKind = DEFAULT_KIND) -> FloatArray:
        """Gripper-to-tip transform at the kind's contact parameters (its ``fields``). Shape (4, 4)."""
        return self.tip_nominal(kind) @ kind.tip_offset(contact)

    def transforms(
        self,
        joints: FloatArray,
        placements: dict[str, FloatArray],
        contact: FloatArray,
        legs_only: bool = False,
        kind: ContactKind = DEFAULT_KIND,
    ) -> tuple[list[FloatArray], FloatArray]:
        """Per-element transforms and the contact offset.

        Args:
            joints: (n, nj) joint angles, rad.
            placements: Placement name -> (6,) parameters.
            contact: The kind's contact parameters (its ``fields``: flush z m, roll rad, pitch rad; point x, y, z m).
            legs_only: Only the elements from the sole up to the root (traversed in reverse);
                the tip is then the identity.
            kind: The contact's kind.

        Returns:
            A list of (n, 4, 4) element transforms and the (4, 4) gripper-to-tip transform.

        """
        n = joints.shape[0]
        out = []
        for k, e in enumerate(self.elements):
            if legs_only and not e.reverse:
                break
            m = placement_matrix(placements[e.name])
            if e.axis is None:
                t = np.broadcast_to(rigid_inverse(m) if e.reverse else m, (n, 4, 4))
            else:
                rot = self._rotations(k, e.axis, joints[:, e.joint])  # (n, 4, 4)
                t = rigid_inverse(m @ rot) if e.reverse else m @ rot
            out.append(t)
        return out, np.eye(4) if legs_only else self.tip(contact, kind)

    def sole_to_contact(
        self,
        joints: FloatArray,
        placements: dict[str, FloatArray],
        contact: FloatArray,
        kind: ContactKind = DEFAULT_KIND,
    ) -> FloatArray:
        """Contact (flush) or point frame, at its offset, in the sole frame. Shape (n, 4, 4)."""
        elements, tip = self.transforms(joints, placements, contact, kind=kind)
        total = elements[0]
        for t in elements[1:]:
            total = total @ t
        return np.asarray(total @ tip)

    def _rotations(self, element: int, axis: FloatArray, angles: FloatArray) -> FloatArray:
        """:func:`_rotations` of an element's joint angles, remembered (fits evaluate the same angles often).

        The arrays returned are read-only: they are shared by every caller with the same angles.
        """
        key = (element, np.ascontiguousarray(angles).tobytes())
        found = self._rotation_cache.get(key)
        if found is None:
            if len(self._rotation_cache) >= ROTATION_CACHE_SIZE:
                self._rotation_cache.clear()
            found = _rotations(axis, angles)
            found.flags.writeable = False
            self._rotation_cache[key] = found
        return found

    def __getstate__(self) -> dict[str, object]:
        state = dict(self.__dict__)
        state["_rotation_cache"] = {}  # a cache, not state: not sent to worker processes
        return state

    def nominal_placements(self) -> dict[str, FloatArray]:
        """Placement name -> nominal (6,) parameters (copies)."""
        return {e.name: e.nominal.copy() for e in self.elements}


def rigid_inverse(transforms: FloatArray) -> FloatArray:
    """Inverse of rigid transforms (..., 4, 4): [R p]^-1 = [R^T -R^T p]."""
    out = np.zeros_like(transforms)
    rot_t = np.swapaxes(transforms[..., :3, :3], -1, -2)
    out[..., :3, :3] = rot_t
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", rot_t, transforms[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


def element_derivatives(element: Element, transforms: FloatArray, params: FloatArray) -> FloatArray:
    """Derivatives of an element's transforms w.r.t. its six placement parameters.

    Args:
        element: The element.
        transforms: (n, 4, 4) its transforms at ``params`` (from :meth:`ChainModel.transforms`).
        params: (6,) its placement parameters.

    Returns:
        (n, 6, 4, 4) derivatives.

    """
    n = transforms.shape[0]
    m = placement_matrix(params)
    d_m = placement_derivatives(params)  # (6, 4, 4)
    if element.axis is None:
        if element.reverse:  # E = M^-1 -> dE = -M^-1 dM M^-1
            m_inv = rigid_inverse(m)
            return np.broadcast_to(-m_inv @ d_m @ m_inv, (n, 6, 4, 4))
        return np.broadcast_to(d_m, (n, 6, 4, 4))
    if element.reverse:  # E = (M R)^-1 -> dE = -E dM M^-1
        return np.asarray(-transforms[:, None] @ (d_m @ rigid_inverse(m))[None])
    return np.asarray(d_m[None] @ (rigid_inverse(m) @ transforms)[:, None])  # E = M R -> dE = dM R


def joint_derivative(element: Element, transforms: FloatArray) -> FloatArray:
    """Derivative of a joint element's transforms w.r.t. its joint angle. Shape (n, 4, 4).

    E = M R(q) gives dE/dq = E K; traversed in reverse, E = R(-q) M^-1 gives -K E, with K
    the (4, 4) generator of rotations about the joint axis.
    """
    assert element.axis is not None, "a fixed placement has no joint angle"
    generator = np.zeros((4, 4))
    generator[:3, :3] = pin.skew(element.axis)
    return np.asarray(-generator @ transforms if element.reverse else transforms @ generator)


ROTATION_CACHE_SIZE = 8192  # joint rotations a chain model remembers (~40 MB at most for 40 postures)


def _rotations(axis: FloatArray, angles: FloatArray) -> FloatArray:
    """Homogeneous rotations about ``axis`` by each angle. Shape (n, 4, 4)."""
    k = np.asarray(pin.skew(axis))
    s = np.sin(angles)[:, None, None]
    c = np.cos(angles)[:, None, None]
    out = np.zeros((len(angles), 4, 4))
    out[:, :3, :3] = np.eye(3) + s * k + (1 - c) * (k @ k)
    out[:, 3, 3] = 1.0
    return out


def _ancestors(model: pin.Model, joint: int) -> list[int]:
    """Joint ids from ``joint`` up to (excluding) the root joint."""
    out = []
    while joint > 1:  # 0 is the universe, 1 the free flyer
        out.append(joint)
        joint = model.parents[joint]
    return out
