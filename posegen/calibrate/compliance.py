"""Compliance compensation: from the encoders' angles to the angles the joints have, and back.

A URDF cannot hold a joint that gives way under load. A calibration whose model has
compliance ships it beside its URDF as ``compliance.yaml``, and this module applies it
exactly as the calibration model does (:meth:`posegen.model.CalibrationModel.deflected`)::

    q_true[j] = q_encoder[j] - c_g * tau_g(q_encoder)      for every joint j of group g

with ``c_g`` the group's compliance (rad/N m; its stiffness is 1 / c_g, N m/rad) and
``tau_g`` the mean over the group's joints of the torque (N m, about each joint's axis,
positive along it) that holds the posture still against gravity: both soles loaded
(the split of the weight between them of least size, forces in N and moments in N m
over a 0.1 m lever weighed alike), the arm in contact unloaded, the URDF's masses
(:func:`posegen.robot.gravity_torques`). A stack with its own estimate of the holding
torques (a whole-body controller's) passes them instead.

The inverse, for commanding a posture: the encoder angles that put the joints at
``q_true`` solve ``q_encoder = q_true + c_g * tau_g(q_encoder)``, by fixed-point
iteration (the deflection changes the torque by a tiny fraction of itself).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from posegen.errors import InputError, reason
from posegen.io import dump_yaml, read_yaml, write_atomic
from posegen.numeric import is_finite_number
from posegen.robot import FloatArray, Scene, gravity_torques

COMPLIANCE_FORMAT = "posegen-compliance"
COMPLIANCE_FILE = "compliance.yaml"
FORMULA = "q_true[j] = q_encoder[j] - c_g * tau_g(q_encoder) for every joint j of group g"
TORQUE_MODEL = (
    "tau_g: mean over the group's joints of the joint torque (N m, about the joint axis, positive along it) that "
    "holds the posture still against gravity, from the URDF's masses (pinocchio); both soles loaded, their wrenches "
    "the least-size split of the weight (forces in N, moments in N m over a 0.1 m lever weighed alike); the arm in "
    "contact unloaded"
)
INVERSE_ITERATIONS = 50  # fixed-point steps of :func:`uncompensate` at most
INVERSE_TOLERANCE_RAD = 1e-13
MAX_COMPLIANCE_RAD_PER_NM = 1.0  # a joint turned a radian by a newton metre holds no robot up (real ones: ~1e-4)


@dataclass(frozen=True)
class ComplianceGroup:
    """Joints that give way together under their mean holding torque."""

    name: str
    joints: tuple[str, ...]
    compliance_rad_per_nm: float
    std_rad_per_nm: float = 0.0  # posterior standard deviation of the calibration

    @property
    def stiffness_nm_per_rad(self) -> float:
        """1 / compliance (inf for a rigid group)."""
        return float("inf") if self.compliance_rad_per_nm == 0.0 else 1.0 / self.compliance_rad_per_nm


@dataclass(frozen=True)
class Compliance:
    """The compliance a calibration found, and the stance its holding torques assume.

    Example:
        >>> compliance = read_compliance("plans/calibration/with_compliance/compliance.yaml")
        >>> true_joints = compensate(scene, encoder_joints, compliance)

    """

    groups: tuple[ComplianceGroup, ...]
    sole_frames: tuple[str, ...]  # both soles loaded

    def indices(self, joint_names: Sequence[str]) -> list[list[int]]:
        """Per group, the indices of its joints in ``joint_names``.

        Raises:
            InputError: A group whose compliance is not a finite number from 0, or joints of
                the compliance that ``joint_names`` lacks (all of them named).

        """
        for group in self.groups:
            if not isinstance(group, ComplianceGroup) or not _compliance(group.compliance_rad_per_nm):
                raise InputError(
                    f"compliance group {getattr(group, 'name', group)!r}: compliance_rad_per_nm must be a finite "
                    f"number from 0 to {MAX_COMPLIANCE_RAD_PER_NM:g} (a joint that gives way under load)"
                )
        missing = sorted({j for g in self.groups for j in g.joints if j not in joint_names})
        if missing:
            raise InputError(f"the compliance names joints the robot does not have: {', '.join(missing)}")
        position = {name: i for i, name in enumerate(joint_names)}
        return [[position[j] for j in g.joints] for g in self.groups]


def _torques(scene: Scene, joints: FloatArray, torques: FloatArray | None) -> FloatArray:
    """The holding torques (n, nj) N m: given (checked), or from the URDF's masses at ``joints``."""
    if torques is None:
        return gravity_torques(scene, joints)
    given = _real_array(torques, "torques")
    if given.shape != joints.shape or not np.all(np.isfinite(given)):
        raise InputError(f"torques: expected finite values of shape {joints.shape}, got {given.shape}")
    return given


def _real_array(values: Any, name: str) -> FloatArray:
    """``values`` as a float array of at least 2 dimensions (a copy), if they are real numbers.

    Raises:
        InputError: Text, complex numbers, booleans or anything else that is not a real number.

    """
    try:
        raw = np.asarray(values)
    except (TypeError, ValueError) as exc:  # ragged nested lists
        raise InputError(f"{name}: expected an array of numbers ({reason(exc)})") from exc
    if raw.dtype.kind not in "fiu":
        raise InputError(f"{name}: expected real numbers (rad or N m), got an array of {raw.dtype}")
    return np.array(raw, dtype=float, ndmin=2)


def _joints(scene: Scene, joints: FloatArray, name: str) -> FloatArray:
    if not isinstance(scene, Scene):
        raise InputError(f"scene: expected a posegen Scene (posegen.load_scene), not {type(scene).__name__}")
    array = _real_array(joints, name)  # a copy: the caller's array is never changed
    if array.ndim != 2 or array.shape[1] != len(scene.joint_names) or not np.all(np.isfinite(array)):
        raise InputError(
            f"{name}: expected finite joint angles of shape (n, {len(scene.joint_names)}) in the scene's joint "
            f"order, got shape {array.shape}"
        )
    return array


def _deflection(compliance: Compliance, indices: list[list[int]], torques: FloatArray) -> FloatArray:
    """c_g * tau_g on every joint of every group (n, nj), rad."""
    out = np.zeros_like(torques)
    for group, joints in zip(compliance.groups, indices, strict=True):
        load = torques[:, joints].mean(axis=1, keepdims=True)  # (n, 1) N m
        out[:, joints] += group.compliance_rad_per_nm * load
    return out


def compensate(
    scene: Scene, joints: FloatArray, compliance: Compliance, torques: FloatArray | None = None
) -> FloatArray:
    """The angles the joints have, from the encoders' angles: ``q - c tau(q)``.

    Args:
        scene: The robot (its joint order and masses).
        joints: (n, nj) or (nj,) encoder angles, rad, in ``scene.joint_names`` order.
        compliance: The calibration's compliance (:func:`read_compliance`).
        torques: (n, nj) holding torques, N m, in the same order; None: from the URDF's
            masses at ``joints`` (the calibration's own model).

    Returns:
        (n, nj) joint angles, rad.

    Raises:
        InputError: Joints the robot lacks, or arrays of the wrong shape or not finite.

    Example:
        >>> true_joints = compensate(scene, encoder_joints, read_compliance("with_compliance/compliance.yaml"))

    """
    q = _joints(scene, joints, "joints")
    indices = _checked(compliance).indices(scene.joint_names)
    return np.asarray(q - _deflection(compliance, indices, _torques(scene, q, torques)))


def uncompensate(
    scene: Scene, joints: FloatArray, compliance: Compliance, torques: FloatArray | None = None
) -> FloatArray:
    """The encoder angles at which the joints have the angles ``joints``: the inverse of :func:`compensate`.

    Args:
        scene: The robot (its joint order and masses).
        joints: (n, nj) or (nj,) true joint angles, rad, in ``scene.joint_names`` order.
        compliance: The calibration's compliance.
        torques: (n, nj) holding torques, N m, at the encoder angles sought; None: from the
            URDF's masses, solved with them (fixed-point iteration).

    Returns:
        (n, nj) encoder angles, rad.

    Raises:
        InputError: Joints the robot lacks, arrays of the wrong shape or not finite, or a
            compliance so large that the iteration does not converge.

    Example:
        >>> command = uncompensate(scene, wanted_joints, compliance)  # what to send to the joint drivers

    """
    target = _joints(scene, joints, "joints")
    indices = _checked(compliance).indices(scene.joint_names)
    if torques is not None:
        return np.asarray(target + _deflection(compliance, indices, _torques(scene, target, torques)))
    encoder = target.copy()
    for _ in range(INVERSE_ITERATIONS):
        step = target + _deflection(compliance, indices, gravity_torques(scene, encoder))
        change = float(np.max(np.abs(step - encoder), initial=0.0))
        encoder = step
        if change <= INVERSE_TOLERANCE_RAD:
            return encoder
    raise InputError(f"uncompensate: no convergence in {INVERSE_ITERATIONS} steps (is the compliance plausible?)")


def compliance_data(compliance: Compliance, urdf: str, provenance: dict[str, Any]) -> dict[str, Any]:
    """The content of ``compliance.yaml``."""
    return {
        "format": COMPLIANCE_FORMAT,
        "format_version": 1,
        "urdf": urdf,
        "formula": FORMULA,
        "torque_model": TORQUE_MODEL,
        "sole_frames": list(compliance.sole_frames),
        "groups": {
            g.name: {
                "joints": list(g.joints),
                "compliance_rad_per_nm": float(g.compliance_rad_per_nm),
                "compliance_rad_per_knm": round(g.compliance_rad_per_nm * 1e3, 6),
                "stiffness_nm_per_rad": None if g.compliance_rad_per_nm == 0.0 else round(g.stiffness_nm_per_rad, 3),
                "std_rad_per_knm": round(g.std_rad_per_nm * 1e3, 6),
            }
            for g in compliance.groups
        },
        "provenance": provenance,
    }


def write_compliance(path: Path, compliance: Compliance, urdf: str, provenance: dict[str, Any]) -> None:
    """Write ``compliance.yaml`` (atomically); ``urdf`` names the URDF it goes with (beside it)."""
    write_atomic(path, dump_yaml(compliance_data(compliance, urdf, provenance)))


def read_compliance(path: str | Path) -> Compliance:
    """Read and check a ``compliance.yaml``.

    Raises:
        InputError: Not a compliance file, or a group without joints or with a compliance
            (or its standard deviation) that is not a finite number from 0.

    Example:
        >>> compliance = read_compliance("plans/calibration/with_compliance/compliance.yaml")

    """
    data = read_yaml(path, COMPLIANCE_FORMAT)
    groups_data = data.get("groups")
    soles = data.get("sole_frames")
    if not isinstance(groups_data, dict) or not isinstance(soles, list) or not all(isinstance(s, str) for s in soles):
        raise InputError(f"{path}: expected 'groups' (a mapping) and 'sole_frames' (a list of frame names)")
    groups = []
    for name, group in groups_data.items():
        joints = group.get("joints") if isinstance(group, dict) else None
        value = group.get("compliance_rad_per_nm") if isinstance(group, dict) else None
        std = group.get("std_rad_per_knm", 0.0) if isinstance(group, dict) else None
        if not isinstance(joints, list) or not joints or not all(isinstance(j, str) for j in joints):
            raise InputError(f"{path}: groups.{name}.joints: expected a non-empty list of joint names")
        if not _compliance(value) or not is_finite_number(std) or std < 0:
            raise InputError(
                f"{path}: groups.{name}: compliance_rad_per_nm must be a finite number from 0 to "
                f"{MAX_COMPLIANCE_RAD_PER_NM:g} and std_rad_per_knm a finite one from 0 (got {value!r}, {std!r})"
            )
        groups.append(ComplianceGroup(str(name), tuple(joints), float(value), float(std) * 1e-3))  # type: ignore[arg-type]
    return Compliance(tuple(groups), tuple(soles))


def _compliance(value: object) -> bool:
    """Whether ``value`` is a compliance: a number from 0 (a negative one would push back) to the largest plausible."""
    return is_finite_number(value) and 0.0 <= float(value) <= MAX_COMPLIANCE_RAD_PER_NM


def _checked(compliance: Compliance) -> Compliance:
    if not isinstance(compliance, Compliance):
        raise InputError(f"compliance: expected a Compliance (read_compliance), not {type(compliance).__name__}")
    return compliance
