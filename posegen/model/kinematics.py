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

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError
from posegen.robot import ContactKind, FloatArray, Scene


def rpy_matrix(phi: FloatArray) -> FloatArray:
    """URDF rpy rotation Rz(phiz) Ry(phiy) Rx(phix). phi: (3,), returns (3, 3)."""
    return np.asarray(pin.rpy.rpyToMatrix(float(phi[0]), float(phi[1]), float(phi[2])))


def _skew(axis: int) -> FloatArray:
    e = np.zeros(3)
    e[axis] = 1.0
    return np.asarray(pin.skew(e))


def rpy_derivatives(phi: FloatArray) -> FloatArray:
    """Derivatives of the rpy rotation with respect to phix, phiy, phiz. Shape (3, 3, 3)."""
    rx = pin.rpy.rpyToMatrix(float(phi[0]), 0.0, 0.0)
    ry = pin.rpy.rpyToMatrix(0.0, float(phi[1]), 0.0)
    rz = pin.rpy.rpyToMatrix(0.0, 0.0, float(phi[2]))
    return np.array([rz @ ry @ rx @ _skew(0), rz @ ry @ _skew(1) @ rx, _skew(2) @ rz @ ry @ rx])


def placement_matrix(params: FloatArray) -> FloatArray:
    """Homogeneous transform of (px, py, pz, phix, phiy, phiz). Shape (4, 4)."""
    out = np.eye(4)
    out[:3, :3] = rpy_matrix(params[3:])
    out[:3, 3] = params[:3]
    return out


def placement_derivatives(params: FloatArray) -> FloatArray:
    """Derivatives of :func:`placement_matrix` w.r.t. its six parameters. Shape (6, 4, 4)."""
    out = np.zeros((6, 4, 4))
    for i in range(3):
        out[i, i, 3] = 1.0
    out[3:, :3, :3] = rpy_derivatives(params[3:])
    return out


def offset_matrix(z: float, roll: float, pitch: float) -> FloatArray:
    """Transform Trans(0, 0, z) Rot_rpy(roll, pitch, 0) (a plane or contact offset). Shape (4, 4)."""
    return placement_matrix(np.array([0.0, 0.0, z, roll, pitch, 0.0]))


def translation_matrix(xyz: FloatArray) -> FloatArray:
    """Transform Trans(x, y, z) (a contact point's offset). Shape (4, 4)."""
    out = np.eye(4)
    out[:3, 3] = xyz
    return out


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
        elements: Placements from the sole to the gripper frame.
        contact_nominal: Nominal flush contact frame in the gripper frame, (4, 4); None
            when the chain declares no flush contact.
        point_nominal: Nominal point frame in the gripper frame, (4, 4); None when the
            chain declares no point contact.
        point_radius_m: The point's tip radius (its centre's height at a contact).
        placement_names: Names of the placements, in chain order.

    """

    def __init__(self, scene: Scene, chain: str) -> None:
        cfg = scene.chain(chain)
        model = scene.model
        self.chain = chain
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
        flush = scene.contact_placements.get(chain)
        point = scene.point_placements.get(chain)
        self.contact_nominal = None if flush is None else np.array(flush.homogeneous)
        self.point_nominal = None if point is None else np.array(point.homogeneous)
        self.contact_frame = cfg.contact_frame
        self.point_frame = cfg.point_frame
        self.point_radius_m = cfg.point_radius_m
        self.placement_names = tuple(e.name for e in elements)
        self._rotation_cache: dict[tuple[int, bytes], FloatArray] = {}

    @property
    def joint_indices(self) -> list[int]:
        """Indices (in Scene.joint_names) of the chain's joints, sole to gripper."""
        return [e.joint for e in self.elements if e.joint is not None]

    def frame(self, kind: ContactKind) -> str:
        """The frame a contact of this kind constrains (flush contact frame or point frame)."""
        return self.point_frame if kind == ContactKind.POINT else self.contact_frame

    def tip_nominal(self, kind: ContactKind) -> FloatArray:
        """Nominal tip frame of a contact kind in the gripper frame. Shape (4, 4).

        Raises:
            ConfigError: The chain declares no contact of this kind.

        """
        tip = self.point_nominal if kind == ContactKind.POINT else self.contact_nominal
        if tip is None:
            needed = "point_frame" if kind == ContactKind.POINT else "fingertip_frames"
            raise ConfigError(f"chains.{self.chain}.{needed}: missing (a {kind.value} contact of this chain needs it)")
        return tip

    def tip(self, contact: FloatArray, kind: ContactKind = ContactKind.FLUSH) -> FloatArray:
        """Gripper-to-tip transform at contact parameters (flush: z, roll, pitch; point: x, y, z). Shape (4, 4)."""
        if kind == ContactKind.POINT:
            return self.tip_nominal(kind) @ translation_matrix(contact)
        return self.tip_nominal(kind) @ offset_matrix(*contact)

    def transforms(
        self,
        joints: FloatArray,
        placements: dict[str, FloatArray],
        contact: FloatArray,
        legs_only: bool = False,
        kind: ContactKind = ContactKind.FLUSH,
    ) -> tuple[list[FloatArray], FloatArray]:
        """Per-element transforms and the contact offset.

        Args:
            joints: (n, nj) joint angles, rad.
            placements: Placement name -> (6,) parameters.
            contact: (3,) contact parameters (flush: z m, roll rad, pitch rad; point: x, y, z m).
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
        kind: ContactKind = ContactKind.FLUSH,
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


def tilt_measurement(frames: FloatArray) -> FloatArray:
    """Height (m), roll and pitch (rad) of frames expressed in the plane frame.

    Args:
        frames: (n, 4, 4) contact frames in the plane frame.

    Returns:
        (n, 3) measurements.

    """
    roll = np.arctan2(frames[:, 2, 1], frames[:, 2, 2])
    pitch = np.arcsin(np.clip(-frames[:, 2, 0], -1.0, 1.0))
    return np.column_stack([frames[:, 2, 3], roll, pitch])


def tilt_measurement_jacobian(row: FloatArray, d_row: FloatArray) -> FloatArray:
    """Derivative of :func:`tilt_measurement` given the third row of the frame.

    Args:
        row: (n, 4) third row of the frame (R20, R21, R22, z).
        d_row: (n, p, 4) its derivatives with respect to p parameters.

    Returns:
        (n, 3, p) derivatives of (z, roll, pitch).

    """
    r20, r21, r22 = row[:, 0, None], row[:, 1, None], row[:, 2, None]
    d_z = d_row[:, :, 3]
    d_roll = (r22 * d_row[:, :, 1] - r21 * d_row[:, :, 2]) / (r21**2 + r22**2)
    d_pitch = -d_row[:, :, 0] / np.sqrt(np.maximum(1.0 - r20**2, 1e-12))
    return np.stack([d_z, d_roll, d_pitch], axis=1)
