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
from posegen.model.chain_pass import ChainPass, chain_pass, joint_rotations, placement_stack, rigid_inverses
from posegen.robot import (
    DEFAULT_KIND,
    ContactKind,
    FloatArray,
    Scene,
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
        self._reverse = np.array([e.reverse for e in elements])
        self._joint = np.array([-1 if e.joint is None else e.joint for e in elements])
        self._axes = np.array([np.zeros(3) if e.axis is None else e.axis for e in elements])
        self._legs = int(np.argmin(self._reverse)) if not self._reverse.all() else len(elements)  # sole .. root
        self._rotation_cache: dict[tuple[int, bytes], FloatArray] = {}
        self._rotation_bytes = 0  # held by the cache

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
        count = self._legs if legs_only else len(self.elements)
        params = np.array([placements[e.name] for e in self.elements[:count]])
        state = self.pass_at(joints, params, legs_only, derivatives=False)
        return list(state.transforms), np.eye(4) if legs_only else self.tip(contact, kind)

    def pass_at(
        self, joints: FloatArray, params: FloatArray, legs_only: bool = False, derivatives: bool = True
    ) -> ChainPass:
        """The chain's elements at n postures in one pass (:mod:`posegen.model.chain_pass`).

        Args:
            joints: (n, nj) joint angles, rad.
            params: (E, 6) placement parameters of the elements, in chain order (the first
                E: the legs' elements alone with ``legs_only``).
            legs_only: Only the elements from the sole up to the root.
            derivatives: Whether the placements' derivatives are needed.

        Example:
            >>> state = chain.pass_at(joints, params)
            >>> frames = state.prefixes[-1] @ chain.tip(contact)  # (n, 4, 4) tip frames in the sole frame

        """
        count = self._legs if legs_only else len(self.elements)
        stack = placement_stack(params[:count], derivatives)
        rotations = self._rotation_stack(joints, count)
        return chain_pass(stack, rotations, self._reverse[:count], self._joint[:count], self._axes[:count])

    def products(self, joints: FloatArray, params: FloatArray, legs_only: bool = False) -> FloatArray:
        """The chain's product ``T_0 ... T_{E-1}`` for F parameter sets at n postures each. Shape (F, n, 4, 4).

        Args:
            joints: (n, nj) joint angles shared by the F sets, or (F, n, nj) each set's own, rad.
            params: (F, E, 6) each set's placement parameters, in chain order.
            legs_only: Only the elements from the sole up to the root.

        Example:
            >>> frames = chain.products(joints, params)[:, :, :, :] @ tip  # (F, n, 4, 4)

        """
        count = self._legs if legs_only else len(self.elements)
        sets = params.shape[0]
        matrices = placement_stack(params[:, :count].reshape(-1, 6), derivatives=False).matrices
        matrices = matrices.reshape(sets, count, 4, 4).transpose(1, 0, 2, 3)[:, :, None]  # (E, F, 1, 4, 4)
        shared = joints if joints.ndim == 2 else joints[0]
        rotations = self._rotation_stack(shared, count)  # (E, n, 4, 4)
        varying = set() if joints.ndim == 2 else set(np.flatnonzero(np.any(joints != shared, axis=(0, 1))))
        total: FloatArray | None = None
        for k in range(count):
            joint = int(self._joint[k])
            if joint in varying:  # this joint's angle is each set's own (a compliant joint's deflection)
                t = matrices[k] @ joint_rotations(self._axes[k : k + 1], joints[:, :, joint].reshape(-1, 1))[0].reshape(
                    sets, -1, 4, 4
                )
            elif joint < 0:
                t = matrices[k]  # a fixed placement: (F, 1, 4, 4), broadcast over the postures
            else:
                t = matrices[k] @ rotations[k]  # (F, n, 4, 4)
            if self._reverse[k]:
                t = rigid_inverses(t)
            total = t if total is None else total @ t
        assert total is not None, "a chain has elements"
        return np.broadcast_to(total, (sets, len(shared), 4, 4))

    def _rotation_stack(self, joints: FloatArray, count: int) -> FloatArray:
        """:meth:`_rotations_at`, remembered (fits evaluate the same angles often). Shape (E, n, 4, 4).

        The arrays returned are read-only: they are shared by every caller with the same angles.
        """
        moving = self._joint[:count] >= 0
        key = (count, np.ascontiguousarray(joints[:, self._joint[:count][moving]]).tobytes())
        found = self._rotation_cache.get(key)
        if found is None:
            found = self._rotations_at(joints, count)
            if self._rotation_bytes + found.nbytes > ROTATION_CACHE_BYTES:
                self._rotation_cache.clear()
                self._rotation_bytes = 0
            self._rotation_bytes += found.nbytes
            found.flags.writeable = False
            self._rotation_cache[key] = found
        return found

    def _rotations_at(self, joints: FloatArray, count: int) -> FloatArray:
        """Joint rotations of the first ``count`` elements at (n, nj) joints; identity for a fixed one. (E, n, 4, 4)."""
        moving = np.flatnonzero(self._joint[:count] >= 0)
        found = np.zeros((count, len(joints), 4, 4))
        found[:] = np.eye(4)
        found[moving] = joint_rotations(self._axes[moving], joints[:, self._joint[moving]])
        return found

    def sole_to_contact(
        self,
        joints: FloatArray,
        placements: dict[str, FloatArray],
        contact: FloatArray,
        kind: ContactKind = DEFAULT_KIND,
    ) -> FloatArray:
        """Contact (flush) or point frame, at its offset, in the sole frame. Shape (n, 4, 4)."""
        params = np.array([placements[e.name] for e in self.elements])
        return np.asarray(self.pass_at(joints, params, derivatives=False).prefixes[-1] @ self.tip(contact, kind))

    def __getstate__(self) -> dict[str, object]:
        state = dict(self.__dict__)
        state["_rotation_cache"], state["_rotation_bytes"] = {}, 0  # a cache, not state: not sent to workers
        return state

    def nominal_placements(self) -> dict[str, FloatArray]:
        """Placement name -> nominal (6,) parameters (copies)."""
        return {e.name: e.nominal.copy() for e in self.elements}


ROTATION_CACHE_BYTES = 64 * 2**20  # rotation stacks a chain model remembers, at most


def _ancestors(model: pin.Model, joint: int) -> list[int]:
    """Joint ids from ``joint`` up to (excluding) the root joint."""
    out = []
    while joint > 1:  # 0 is the universe, 1 the free flyer
        out.append(joint)
        joint = model.parents[joint]
    return out
