"""Simulated contacts on a perturbed "true" robot (``posegen simulate``).

The true robot is the nominal model with seeded random errors on every placement
parameter, on the contact offsets and on the table plane, and (if asked) joint
compliance: every compliance group of the config gives way under gravity. At each
planned posture the real experiment's physics is reproduced:

* both soles stay flat on the floor where the reference posture puts them: the second
  leg's joints take whatever angles close the true chain (the floor, not the nominal
  model, holds the feet); when the second leg alone cannot (its knee nearly stretched,
  the true leg a little short), both legs do, the pelvis moving as a standing robot's;
* the force-controlled contact moves the chain's own arm and torso joints by the
  smallest amount that makes the true contact frame flush with the true plane;
* no joint goes past its limit (by more than a recording reads, ``LIMIT_TOLERANCE_RAD``):
  one that would stops there, and the others settle;

both under the true robot's deflection by gravity (Levenberg-Marquardt, minimum-norm
steps, the gravity torques recomputed until the angles stop moving). The encoders then
read those angles plus noise. A posture the true robot still cannot take is left out and
logged with why (a closure left open and by how much, or a joint past its limit).

Contact noise (the table's unevenness, the fingertips, the force control: what a real
calibration reports on top of the encoders') is physical too: each contact settles flush
on its own local plane, the true table offset in height and tilted in roll and pitch by
seeded normal draws (:func:`contact_offsets`), so the recorded joints carry it. The draw
is a function of the seed and the posture (the same posture, to 1e-6 rad, touches the
same local plane whichever plan holds it; a route's hold, a few mrad from the planned
posture after its go-to-contact, is another posture and gets another draw).
"""

from __future__ import annotations

import hashlib
import logging
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from posegen.errors import InfeasibleError, InputError
from posegen.model import (
    LIMIT_TOLERANCE_RAD,
    CalibrationModel,
    Contacts,
    Group,
    Kind,
    Parameter,
    Unit,
    row_mask,
)
from posegen.robot import ContactKind, FloatArray, Scene

LOG = logging.getLogger(__name__)
CONTACT_TOLERANCE = 1e-11  # m or rad: the true contact and floor closure are exact to this
MAX_STEPS = 60


@dataclass(frozen=True)
class Perturbation:
    """Sizes of the simulated errors."""

    length_m: float = 2e-3  # sigma of placement length errors
    angle_rad: float = float(np.deg2rad(0.5))  # sigma of placement angle errors
    max_angle_rad: float = float(np.deg2rad(1.5))  # angle errors are clipped here
    plane_height_m: float | None = None  # true table height above the soles; None: the scene's table
    plane_tilt_rad: float = float(np.deg2rad(0.5))  # sigma of the table's roll and pitch
    encoder_noise_rad: float = 0.0  # sigma of the encoder readings' noise
    compliance_rad_per_nm: float = 0.0  # true compliance of the compliance groups below
    compliance_groups: tuple[str, ...] = ()  # of the config's calibration.compliance; empty: its first group
    contact_noise_m: float = 0.0  # sigma of each contact's local table height (its own plane's offset)
    contact_noise_rad: float = 0.0  # sigma of each contact's local table roll and pitch


def true_parameters(model: CalibrationModel, perturbation: Perturbation, seed: int) -> FloatArray:
    """Nominal parameters plus seeded random errors; floor constants those of the reference stance. Shape (nx,)."""
    rng = np.random.default_rng(seed)
    contact = model.contact
    x = model.nominal()
    for i, p in enumerate(contact.parameters):
        if p.group == Group.PLANE:
            continue
        if p.unit == Unit.LENGTH:
            x[i] += rng.normal(0.0, perturbation.length_m)
        else:
            x[i] += float(
                np.clip(
                    rng.normal(0.0, perturbation.angle_rad), -perturbation.max_angle_rad, perturbation.max_angle_rad
                )
            )
    height = perturbation.plane_height_m
    if height is None:
        height = float(model.scene.table_pose[2, 3])
    for session in model.sessions:
        x[contact.column(Parameter.plane(session, "z"))] = height
        for field in ("roll", "pitch"):
            x[contact.column(Parameter.plane(session, field))] = rng.normal(0.0, perturbation.plane_tilt_rad)
    x[model.columns([Kind.COMPLIANCE])] = perturbation.compliance_rad_per_nm
    scene = model.scene
    relative = np.linalg.inv(scene.sole_poses[scene.anchor_sole]) @ scene.sole_poses[scene.second_sole]
    for session in model.sessions:
        x[model.floor_columns(session)] = floor_constants(relative)
    return x


def floor_constants(relative: FloatArray) -> tuple[float, float, float]:
    """A session's floor constants: the second sole's x, y (m) and yaw (rad) in the anchor sole's frame.

    Args:
        relative: The second sole's pose (4, 4) in the anchor sole's frame (both flat on the floor).

    Example:
        >>> floor_constants(np.array([[0, -1, 0, 0.01], [1, 0, 0, -0.2], [0, 0, 1, 0], [0, 0, 0, 1.0]]))
        (0.01, -0.2, 1.5707963267948966)

    """
    return float(relative[0, 3]), float(relative[1, 3]), float(np.arctan2(relative[1, 0], relative[0, 0]))


def contact_offsets(planned: Contacts, perturbation: Perturbation, seed: int) -> FloatArray:
    """Each contact's local plane: height (m), roll, pitch (rad) off the true table's. Shape (n, 3).

    Normal draws of the perturbation's contact noise, from the seed and the posture (its
    chain and joint angles to 1e-6 rad): the same posture gets the same local plane. A
    point contact's roll and pitch are not measured and stay 0. Zeros without contact noise.
    """
    offsets = np.zeros((len(planned), 3))
    sigma = np.array([perturbation.contact_noise_m, perturbation.contact_noise_rad, perturbation.contact_noise_rad])
    if not np.any(sigma):
        return offsets
    for i, (chain, joints) in enumerate(zip(planned.chains, planned.joints, strict=True)):
        rounded = np.round(np.asarray(joints, dtype=np.float64) * 1e6).astype(np.int64)
        digest = hashlib.sha256(chain.encode() + b"\0" + rounded.astype("<i8").tobytes()).digest()
        rng = np.random.default_rng([seed, 3, int.from_bytes(digest[:8], "little")])  # [seed, 1], [seed, 2]: noise
        offsets[i] = rng.normal(0.0, 1.0, 3) * sigma
    return np.where(row_mask(planned.kinds), offsets, 0.0)


class _TrueSettle:
    """The residuals a true robot's posture settles to zero: its contacts on their local planes, its soles flat."""

    locked: NDArray[np.bool_]  # (n, nj) joints held at a limit in the current solve

    def __init__(
        self, model: CalibrationModel, x: FloatArray, planned: Contacts, stand: bool, offsets: FloatArray | None
    ) -> None:
        self.model, self.x, self.planned = model, x, planned
        self.floor = model.floor if stand else None
        self.local = np.zeros((len(planned), 3)) if offsets is None else np.asarray(offsets, dtype=float)  # (n, 3)
        self.target = np.zeros((len(planned), 6))  # floor: x, y, yaw of the session
        # a joint stays within its limits, as far past them as recordings read (or where the plan put it)
        scene = model.scene
        self.lower = np.minimum(scene.lower - LIMIT_TOLERANCE_RAD, planned.joints)  # (n, nj) rad
        self.upper = np.maximum(scene.upper + LIMIT_TOLERANCE_RAD, planned.joints)
        sessions = np.array(planned.sessions)
        for session in set(planned.sessions):
            self.target[np.ix_(sessions == session, [0, 1, 5])] = x[model.floor_columns(session)]

    def own(self, legs: Sequence[str]) -> dict[str, list[int]]:
        """Chain -> the joints a posture of it moves: its arm and torso, and the legs of ``legs`` (soles)."""
        scene = self.model.scene
        stance = set(scene.stance_leg_joints())
        moved = sorted({j for sole in legs for j in scene.leg_joints(sole)}) if self.floor is not None else []
        return {name: sorted(set(c.joint_indices) - stance) + moved for name, c in self.model.contact.chains.items()}

    def residuals(self, rows: NDArray[np.intp], values: FloatArray, jacobian: bool) -> tuple[FloatArray, FloatArray]:
        """Contact and floor residuals of some postures (m, 3 or 9) and, gravity torques held, joint derivatives."""
        model, x, floor = self.model, self.x, self.floor
        posture = self.planned.subset(rows)
        observations = model.observations(posture.at(values[rows]))
        if not jacobian:
            out = model.evaluate(x, observations, floor=floor is not None)
            floor_blocks = [out.floor] if floor is not None else []  # floor: less its session's
            return np.concatenate([out.contact - self.local[rows], *floor_blocks], axis=1), np.zeros(0)
        bent = posture.at(model.deflected(x, observations))
        theta = model.theta(x)
        res, _, d_joints = model.contact.derivatives(theta, bent)
        blocks, jacs = [res - self.local[rows]], [d_joints]
        if floor is not None:
            pose, _, f_joints = floor.derivatives(theta, bent.joints)
            blocks.append(pose - self.target[rows])
            jacs.append(f_joints)
        return np.concatenate(blocks, axis=1), np.concatenate(jacs, axis=1)

    def solve(
        self, joints: FloatArray, rows: NDArray[np.intp], own: dict[str, list[int]]
    ) -> tuple[FloatArray, FloatArray]:
        """Levenberg-Marquardt on each posture's own joints (minimum-norm steps); the joints and residuals (n, m).

        A posture stops when it settles (every residual below CONTACT_TOLERANCE) or when no
        step helps even heavily damped (stalled). A step that would take a joint past its
        limit stops it there, and the posture's other joints settle without it.
        """
        joints = joints.copy()
        self.locked = np.zeros(joints.shape, dtype=bool)  # (n, nj) joints held at a limit
        residual = np.full((len(self.planned), 9 if self.floor is not None else 3), np.inf)
        jacobian = np.zeros((len(self.planned), residual.shape[1], joints.shape[1]))
        residual[rows], jacobian[rows] = self.residuals(rows, joints, True)
        damping = np.full(len(self.planned), 1e-6)  # per posture
        active = np.zeros(len(self.planned), dtype=bool)
        active[rows] = np.abs(residual[rows]).max(axis=1) >= CONTACT_TOLERANCE
        for _ in range(MAX_STEPS):
            moving = np.flatnonzero(active)
            if not len(moving):
                break
            joints, improved = self._step(joints, moving, residual, jacobian, damping, own)
            res, jac = self.residuals(moving, joints, True)
            residual[moving], jacobian[moving] = res, jac
            active[moving] = np.abs(res).max(axis=1) >= CONTACT_TOLERANCE
            active[moving[~improved]] = False  # no step helps even heavily damped: stalled
        return joints, residual

    def _step(
        self,
        joints: FloatArray,
        rows: NDArray[np.intp],
        residual: FloatArray,
        jacobian: FloatArray,
        damping: FloatArray,
        own: dict[str, list[int]],
    ) -> tuple[FloatArray, NDArray[np.bool_]]:
        """One damped step of every posture in ``rows``, the damping raised until the residual falls (or capped)."""
        norm = np.linalg.norm(residual[rows], axis=1)
        pending = np.ones(len(rows), dtype=bool)
        improved = np.zeros(len(rows), dtype=bool)
        trial = joints.copy()
        stopped = np.zeros(joints.shape, dtype=bool)  # (n, nj) joints the trial step stops at a limit
        for _attempt in range(20):  # damping from 1e-6 up to its cap
            for k in np.flatnonzero(pending):
                i = rows[k]
                cols = [c for c in own[self.planned.chains[i]] if not self.locked[i, c]]
                a = jacobian[i][:, cols]
                step = joints[i, cols] - a.T @ np.linalg.solve(a @ a.T + damping[i] * np.eye(a.shape[0]), residual[i])
                trial[i, cols] = np.clip(step, self.lower[i, cols], self.upper[i, cols])
                stopped[i, cols] = trial[i, cols] != step
            new, _ = self.residuals(rows[pending], trial, False)
            better = np.zeros(len(rows), dtype=bool)
            better[pending] = np.linalg.norm(new, axis=1) < norm[pending]
            worse = pending & ~better
            improved |= better
            self.locked[rows[better]] |= stopped[rows[better]]
            damping[rows[better]] = np.maximum(damping[rows[better]] / 3.0, 1e-12)
            damping[rows[worse]] *= 4.0
            trial[rows[worse]] = joints[rows[worse]]
            pending = worse & (damping[rows] < 1e6)
            if not np.any(pending):
                break
        return trial, improved


def settle_true(
    model: CalibrationModel,
    x: FloatArray,
    planned: Contacts,
    stand: bool = True,
    offsets: FloatArray | None = None,
) -> tuple[Contacts, NDArray[np.bool_], FloatArray]:
    """Joint angles at which each planned posture stands and touches under parameters ``x``.

    The contact settles by the chain's arm and torso; the second sole by the second leg
    (the anchor leg keeps its planned angles). A posture whose second leg cannot close
    the floor alone (a leg too short for its stretched knee under the true robot's
    lengths) settles again from its planned angles with both legs free: the pelvis moves,
    as a standing robot's does. With ``stand`` false the legs keep their planned angles
    and only the contacts settle (a route's rehearsal, whose legs follow the planned
    trajectory). ``offsets`` (n, 3): each contact settles flush on its local plane, this
    far (height m, roll, pitch rad) from the true table (:func:`contact_offsets`); None: on
    the true table.

    Returns:
        The settled postures, which of them converged (n,), and their residuals (n, 3) or
        (n, 9): the contact's (m, rad, rad), then the second sole's (m, m, m, rad, rad, rad).

    """
    settle = _TrueSettle(model, x, planned, stand, offsets)
    scene = model.scene
    everything = np.arange(len(planned))
    joints, residual = settle.solve(planned.joints, everything, settle.own([scene.second_sole]))
    retry = np.flatnonzero(np.abs(residual).max(axis=1) >= 1e-9) if settle.floor is not None else np.zeros(0, int)
    if len(retry):  # the second leg alone cannot close the floor: both legs move (the pelvis too)
        both = settle.own([scene.anchor_sole, scene.second_sole])
        again, again_residual = settle.solve(planned.joints, retry, both)
        joints[retry], residual[retry] = again[retry], again_residual[retry]
    converged = np.abs(residual).max(axis=1) < 1e-9
    return planned.at(joints), converged, residual


def perturbed_robot(
    scene: Scene,
    chains: Sequence[str],
    sessions: Sequence[str],
    perturbation: Perturbation,
    seed: int,
    kinds: Mapping[str, Sequence[ContactKind]] | None = None,
) -> tuple[CalibrationModel, FloatArray]:
    """The true robot of a simulation: its model (with the perturbation's compliance groups) and parameters.

    ``kinds`` (chain -> contact kinds) gives the contact parameters the true robot has;
    None: the kind ``pool`` plans for each chain.

    Raises:
        InputError: A compliance group that the config does not define.

    """
    groups = {}
    if perturbation.compliance_rad_per_nm:
        configured = scene.calibration.compliance
        names = perturbation.compliance_groups or tuple(configured)[:1]
        unknown = [g for g in names if g not in configured]
        if unknown or not names:
            raise InputError(
                f"compliance groups {unknown or '(none)'} are not in calibration.compliance: {', '.join(configured)}"
            )
        groups = {g: configured[g] for g in names}
    model = CalibrationModel(scene, sorted(set(chains)), sorted(set(sessions)), groups, kinds)
    return model, true_parameters(model, perturbation, seed)


def simulate(
    scene: Scene, planned: Contacts, perturbation: Perturbation, seed: int
) -> tuple[Contacts, CalibrationModel, FloatArray]:
    """Recorded contacts of a perturbed robot at planned postures.

    Args:
        scene: Scene of the nominal robot (the perturbation's compliance groups, from
            its config, give way under gravity).
        planned: Planned postures (chains, sessions, joints), standing on both soles.
        perturbation: Error sizes.
        seed: Seed of the errors and of the encoder noise.

    Returns:
        The recorded contacts (settled joints, on their local planes with contact noise,
        plus encoder noise; a posture the perturbed robot cannot take is left out and
        logged with why: :func:`left_out_reason`), the model and the true parameter
        vector (nx,).

    Raises:
        InfeasibleError: No posture can be reached.

    """
    model, x = perturbed_robot(scene, planned.chains, planned.sessions, perturbation, seed, planned.kinds_by_chain())
    offsets = contact_offsets(planned, perturbation, seed)
    settled, converged, residual = settle_true(model, x, planned, offsets=offsets)
    # a joint the true robot would have to take past its limits (a knee stretched backwards) cannot be recorded
    beyond = (settled.joints < scene.lower - LIMIT_TOLERANCE_RAD) | (settled.joints > scene.upper + LIMIT_TOLERANCE_RAD)
    converged = converged & ~beyond.any(axis=1)
    if not np.any(converged):
        raise InfeasibleError("no planned posture stands and touches the table on the perturbed robot")
    for i in np.flatnonzero(~converged):
        why = left_out_reason(scene, settled.joints[i], residual[i])
        LOG.warning("planned posture %d (%s) left out: %s", i, planned.labels[i], why)
    settled = settled.subset(np.flatnonzero(converged))
    rng = np.random.default_rng([seed, 1])
    noisy = settled.joints + rng.normal(0.0, perturbation.encoder_noise_rad, settled.joints.shape)
    return settled.at(noisy), model, x


def left_out_reason(scene: Scene, joints: FloatArray, residual: FloatArray) -> str:
    """Why a posture the true robot cannot take is left out: a joint past its limit, or a closure left open.

    Args:
        scene: The robot.
        joints: (nj,) the settled joint angles, rad.
        residual: (3,) or (9,) what remains of the contact (m, rad, rad) and, standing, the
            second sole's closure (m, m, m, rad, rad, rad).

    Example:
        >>> left_out_reason(scene, settled.joints[i], residual[i])
        'the second sole stays 3.21 mm, 0.04 deg off the floor (no angles of the legs close it)'

    """
    over = np.maximum(scene.lower - LIMIT_TOLERANCE_RAD - joints, joints - scene.upper - LIMIT_TOLERANCE_RAD)
    if np.any(over > 0.0):
        j = int(np.argmax(over))
        return f"joint {scene.joint_names[j]} past its limit by {over[j] + LIMIT_TOLERANCE_RAD:.4f} rad"
    contact, floor = residual[:3], residual[3:]
    if floor.size and np.abs(floor).max() >= np.abs(contact).max():
        mm, deg = np.abs(floor[:3]).max() * 1e3, np.degrees(np.abs(floor[3:]).max())
        return f"the second sole stays {mm:.2f} mm, {deg:.2f} deg off the floor (no angles of the legs close it)"
    mm, deg = abs(contact[0]) * 1e3, np.degrees(np.abs(contact[1:]).max())
    return f"the contact stays {mm:.2f} mm, {deg:.2f} deg off its table (out of reach of the arm and torso)"
