"""Every measurement of a standing-contact experiment, over one parameter vector.

The parameter vector is ``x = [theta | compliance | floor constants]``: theta is the
contact model's (every placement, the contact offsets, a plane per session), then one
compliance per group of joints (rad/N m), then the second sole's x, y (m) and yaw
(rad) per session. Two measurement kinds read it:

* contacts: height (m), roll and pitch (rad) of each contact frame in its session's
  plane, zero at a flush contact (a point contact: its height only, the other two rows
  zero);
* floors: the second sole's pose in the first sole's frame, less (x, y, 0, 0, 0, yaw)
  of its session, zero when both soles are flat on one floor.

Both are evaluated at the deflected joints q - c tau(q): the joints of a compliance group
give way together under gravity, by the group's compliance (rad/N m, positive) times
the mean of their holding torques (:mod:`posegen.robot.statics`), in the direction
gravity pulls. A group of one joint is a joint spring; a group of joints on one axis
line is springs in parallel: both hip pitch joints of a robot standing on its two feet
share their axis, and the pelvis pitching on them under the upper body's weight keeps
both soles flat (a deflection the floor equations allow), whatever the split of the
weight between the feet.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from dataclasses import field as dataclass_field

import numpy as np

from posegen.errors import InfeasibleError
from posegen.model.contact_model import ContactModel, Contacts
from posegen.model.floor_model import SESSION_FIELDS, FloorModel
from posegen.model.kinds import Direction, Kind, Part, kind_basis
from posegen.model.kinematics import ChainModel
from posegen.model.planes import initial_planes
from posegen.robot import Config, ContactKind, FloatArray, Indices, Scene, gravity_torques


@dataclass(frozen=True)
class Observations:
    """Contacts and the gravity torques of their postures (computed once)."""

    contacts: Contacts
    torques: FloatArray  # (n, nj) N m, zero where no joint is compliant
    _loads: dict[tuple[int, ...], FloatArray] = dataclass_field(default_factory=dict, compare=False, repr=False)

    def __len__(self) -> int:
        return len(self.contacts)

    def load(self, joints: Sequence[int]) -> FloatArray:
        """Mean holding torque of some joints at each posture (n,) N m (computed once per set of joints)."""
        key = tuple(joints)
        found = self._loads.get(key)
        if found is None:
            found = self.torques[:, list(key)].mean(axis=1)
            self._loads[key] = found
        return found

    def subset(self, rows: Indices) -> Observations:
        """The observations at the given row indices (copies)."""
        idx = [int(i) for i in rows]
        return Observations(self.contacts.subset(idx), self.torques[idx].copy())


@dataclass(frozen=True)
class Evaluation:
    """Residuals of both measurement kinds and, if asked for, their derivatives w.r.t. x."""

    contact: FloatArray  # (n, 3) m, rad, rad
    floor: FloatArray  # (n, 6) m, m, m, rad, rad, rad; (n, 0) without a floor model
    contact_jacobian: FloatArray  # (n, 3, nx), or (n, 3, 0) when not asked for
    floor_jacobian: FloatArray  # (n, 6, nx), or (n, 6, 0)


def body_parts(scene: Scene, model: ContactModel) -> dict[str, Part]:
    """Placement name -> part: sole up to the root is leg, what every configured chain shares is torso."""
    chains = [ChainModel(scene, c.name) for c in scene.chains]
    forward = [{e.name for e in chain.elements if not e.reverse} for chain in chains]
    shared = set.intersection(*forward) if len(forward) > 1 else set()
    parts: dict[str, Part] = {}
    for chain in model.chains.values():
        for element in chain.elements:
            parts[element.name] = Part.LEG if element.reverse else Part.TORSO if element.name in shared else Part.ARM
    return parts


class CalibrationModel:
    """Contacts and floor closures of some chains and sessions, with joint compliance.

    Attributes:
        contact: The contact model (theta's layout).
        floor: The floor closure, or None when the chains do not reach both soles.
        compliance: Compliance group -> indices (in the scene's joints) of its joints.
        directions: The kind basis' directions (:mod:`posegen.model.kinds`), one per entry of x.
        basis: (nx, nx) x = x_nominal + basis @ delta.

    """

    def __init__(
        self,
        scene: Scene,
        chains: Sequence[str],
        sessions: Sequence[str],
        compliance: Mapping[str, Sequence[str]],
        kinds: Mapping[str, Sequence[ContactKind]] | None = None,
    ) -> None:
        self.scene = scene
        self._arguments = (tuple(chains), tuple(sessions), {g: tuple(j) for g, j in compliance.items()}, kinds)
        self.contact = ContactModel(scene, chains, sessions, kinds)
        self.floor: FloorModel | None
        try:
            self.floor = FloorModel(self.contact)
        except InfeasibleError:
            self.floor = None
        self.compliance = {group: [scene.joint_index(j) for j in joints] for group, joints in compliance.items()}
        self.sessions = self.contact.sessions
        self.directions: tuple[Direction, ...]
        self.directions, self.basis = kind_basis(
            self.contact, body_parts(scene, self.contact), list(self.compliance), self.sessions
        )
        self.size = self.basis.shape[0]
        self._basis_inverse = np.linalg.inv(self.basis)
        self._compliance_start = self.contact.size
        self._floor_start = self.contact.size + len(self.compliance)

    def __reduce__(self) -> tuple[object, tuple[object, ...]]:
        """Pickled as its scene's config and arguments, rebuilt on loading (worker processes).

        The pinocchio model itself does not always survive pickling (some joint types fail to
        load back), and the config is far smaller.
        """
        return (_rebuild, (self.scene.config, *self._arguments))

    def nominal(self) -> FloatArray:
        """The URDF, no compliance, floor constants zero. Shape (nx,)."""
        return np.concatenate([self.contact.nominal(), np.zeros(self.size - self.contact.size)])

    def x_of(self, delta: FloatArray) -> FloatArray:
        """Parameters at deviations ``delta`` along the directions. Shape (nx,)."""
        return np.asarray(self.nominal() + self.basis @ delta)

    def delta_of(self, x: FloatArray) -> FloatArray:
        """Deviations along the directions of parameters ``x`` (first order for rotations). Shape (nx,)."""
        return np.asarray(self._basis_inverse @ (x - self.nominal()))

    def theta(self, x: FloatArray) -> FloatArray:
        """The contact model's parameters within x (a copy). Shape (p,)."""
        return np.array(x[: self.contact.size])

    def compliances(self, x: FloatArray) -> dict[str, float]:
        """Compliance group -> rad/N m."""
        return {g: float(x[self._compliance_start + k]) for k, g in enumerate(self.compliance)}

    def floor_columns(self, session: str) -> list[int]:
        """Columns of a session's floor constants (x, y, yaw) in x."""
        start = self._floor_start + 3 * self.sessions.index(session)
        return list(range(start, start + len(SESSION_FIELDS)))

    def columns(self, kinds: Sequence[Kind]) -> list[int]:
        """Directions (columns of the basis) of the given kinds."""
        return [i for i, d in enumerate(self.directions) if d.kind in kinds]

    def observations(self, contacts: Contacts) -> Observations:
        """Contacts with the gravity torques of their postures (zero when nothing is compliant)."""
        if not self.compliance:
            return Observations(contacts, np.zeros(contacts.joints.shape))
        return Observations(contacts, gravity_torques(self.scene, contacts.joints))

    def deflected(self, x: FloatArray, observations: Observations) -> FloatArray:
        """Joint angles under gravity, q - c mean(tau) per group. Shape (n, nj)."""
        joints = observations.contacts.joints.copy()
        for k, indices in enumerate(self.compliance.values()):
            load = observations.load(indices)[:, None]  # (n, 1) N m
            joints[:, indices] -= x[self._compliance_start + k] * load
        return joints

    def evaluate(
        self, x: FloatArray, observations: Observations, jacobian: bool = False, floor: bool = True
    ) -> Evaluation:
        """Residuals of the contacts and (if ``floor``) the floors, and their derivatives w.r.t. x if ``jacobian``."""
        contacts = observations.contacts
        n = len(contacts)
        bent = contacts.at(self.deflected(x, observations))
        theta = self.theta(x)
        floor_offset = np.zeros((n, 6))
        sessions = np.array(contacts.sessions)
        model = self.floor if floor else None
        if model is not None:
            for session in set(contacts.sessions):
                x0, y0, yaw0 = x[self.floor_columns(session)]
                floor_offset[sessions == session] = (x0, y0, 0.0, 0.0, 0.0, yaw0)
        if not jacobian:
            contact = self.contact.residuals(theta, bent)
            if model is None:
                return Evaluation(contact, np.zeros((n, 0)), np.zeros((n, 3, 0)), np.zeros((n, 6, 0)))
            measured = model.measure(theta, bent.joints) - floor_offset
            return Evaluation(contact, measured, np.zeros((n, 3, 0)), np.zeros((n, 6, 0)))
        contact, d_theta, d_joints = self.contact.derivatives(theta, bent)
        contact_jac = np.zeros((n, 3, self.size))
        contact_jac[:, :, : self.contact.size] = d_theta
        self._compliance_columns(contact_jac, d_joints, observations)
        if model is None:
            return Evaluation(contact, np.zeros((n, 0)), contact_jac, np.zeros((n, 6, 0)))
        pose, f_theta, f_joints = model.derivatives(theta, bent.joints)
        floor_jac = np.zeros((n, 6, self.size))
        floor_jac[:, :, : self.contact.size] = f_theta
        self._compliance_columns(floor_jac, f_joints, observations)
        for session in set(contacts.sessions):
            rows = np.flatnonzero(sessions == session)
            for field, col in zip((0, 1, 5), self.floor_columns(session), strict=True):
                floor_jac[rows, field, col] = -1.0
        return Evaluation(contact, pose - floor_offset, contact_jac, floor_jac)

    def evaluate_batch(
        self, xs: FloatArray, observations: Observations, floor: bool = True
    ) -> tuple[FloatArray, FloatArray]:
        """Residuals of F parameter vectors (F, nx) at once: contacts (F, n, 3) and floors (F, n, 6) or (F, n, 0).

        The same numbers as :meth:`evaluate` of each vector (a fold's refits evaluate many at once).

        Example:
            >>> contact, floor = model.evaluate_batch(np.stack([x, y]), observations)  # contact[1]: evaluate(y).contact

        """
        sets, n = xs.shape[0], len(observations)
        joints = None
        if self.compliance:
            joints = np.broadcast_to(observations.contacts.joints, (sets, *observations.contacts.joints.shape)).copy()
            for k, indices in enumerate(self.compliance.values()):
                load = observations.load(indices)  # (n,) N m
                joints[:, :, indices] -= xs[:, self._compliance_start + k, None, None] * load[None, :, None]
        thetas = xs[:, : self.contact.size]
        contact = self.contact.residuals_batch(thetas, observations.contacts, joints)
        if not floor or self.floor is None:
            return contact, np.zeros((sets, n, 0))
        measured = self.floor.measure_batch(thetas, observations.contacts.joints if joints is None else joints)
        sessions = np.array(observations.contacts.sessions)
        for session in set(observations.contacts.sessions):
            rows = sessions == session
            constants = xs[:, self.floor_columns(session)]  # (F, 3) x, y, yaw
            measured[:, rows] -= np.stack(
                [constants[:, 0], constants[:, 1], *np.zeros((3, sets)), constants[:, 2]], axis=1
            )[:, None]
        return contact, measured

    def _compliance_columns(self, jac: FloatArray, d_joints: FloatArray, observations: Observations) -> None:
        """Add d residual / d compliance = -(sum over the group's joints of d residual / d q_j) * mean tau."""
        for k, indices in enumerate(self.compliance.values()):
            load = observations.load(indices)  # (n,) N m
            jac[:, :, self._compliance_start + k] = -d_joints[:, :, indices].sum(axis=2) * load[:, None]


def _rebuild(
    config: Config,
    chains: Sequence[str],
    sessions: Sequence[str],
    compliance: Mapping[str, Sequence[str]],
    kinds: Mapping[str, Sequence[ContactKind]] | None,
) -> CalibrationModel:
    """A calibration model built again from its scene's config (see :meth:`CalibrationModel.__reduce__`)."""
    return CalibrationModel(Scene(config), chains, sessions, compliance, kinds)


def start_point(model: CalibrationModel, observations: Observations) -> FloatArray:
    """The URDF with each session's plane level at its contacts' mean height, floor constants as measured."""
    contacts = observations.contacts
    x = model.nominal()
    x[: model.contact.size] = initial_planes(model.contact, contacts, model.theta(x))
    if model.floor is not None:
        pose = model.floor.measure(model.theta(x), contacts.joints)
        sessions = np.array(contacts.sessions)
        for session in set(contacts.sessions):
            x[model.floor_columns(session)] = pose[sessions == session][:, [0, 1, 5]].mean(axis=0)
    return x
