"""The plane-constrained measurement model of one or more chains and table sessions.

Parameters (a flat vector, named): every placement of every chain (shared placements,
such as the torso's, appear once), each chain's contact offsets, and one plane per
table session. Residuals of a set of contacts: (n, 3) height (m), roll, pitch (rad) of
each contact frame in its session's plane frame.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from posegen.model.kinematics import (
    ChainModel,
    element_derivatives,
    joint_derivative,
    offset_matrix,
    placement_derivatives,
    rigid_inverse,
    tilt_measurement,
    tilt_measurement_jacobian,
)
from posegen.model.parameters import OFFSET_FIELDS, PLACEMENT_FIELDS, Group, Parameter
from posegen.robot import FloatArray, Indices, Scene


@dataclass(frozen=True)
class Contacts:
    """Recorded (or simulated) flush contacts."""

    joints: FloatArray  # (n, nj) rad, in the scene's joint order
    chains: tuple[str, ...]  # chain in contact, per contact
    sessions: tuple[str, ...]  # table session (one plane each), per contact
    labels: tuple[str, ...]  # e.g. target spot or source row, per contact

    def __len__(self) -> int:
        return len(self.chains)

    def subset(self, rows: Indices) -> Contacts:
        """The contacts at the given row indices (copies)."""
        idx = [int(i) for i in rows]
        return Contacts(
            joints=self.joints[idx].copy(),
            chains=tuple(self.chains[i] for i in idx),
            sessions=tuple(self.sessions[i] for i in idx),
            labels=tuple(self.labels[i] for i in idx),
        )

    def concat(self, other: Contacts) -> Contacts:
        """These contacts followed by ``other``."""
        return Contacts(
            joints=np.vstack([self.joints, other.joints]),
            chains=self.chains + other.chains,
            sessions=self.sessions + other.sessions,
            labels=self.labels + other.labels,
        )


class ContactModel:
    """Measurement model of contacts of some chains at some table sessions."""

    def __init__(self, scene: Scene, chains: Sequence[str], sessions: Sequence[str]) -> None:
        self.scene = scene
        self.chains = {c: ChainModel(scene, c) for c in dict.fromkeys(chains)}
        self.sessions = tuple(dict.fromkeys(sessions))
        params: list[Parameter] = []
        nominal: list[float] = []
        seen: set[str] = set()
        for model in self.chains.values():
            for element in model.elements:
                if element.name in seen:
                    continue  # shared with an earlier chain (torso)
                seen.add(element.name)
                for field, value in zip(PLACEMENT_FIELDS, element.nominal, strict=True):
                    params.append(Parameter.placement(element.name, field))
                    nominal.append(float(value))
        for model in self.chains.values():
            for field in OFFSET_FIELDS:
                params.append(Parameter.contact(model.contact_frame, field))
                nominal.append(0.0)
        for session in self.sessions:
            for field in OFFSET_FIELDS:
                params.append(Parameter.plane(session, field))
                nominal.append(0.0)
        self.parameters = tuple(params)
        self.index = {p.name: i for i, p in enumerate(params)}  # parameter name -> column
        self._columns = {p: i for i, p in enumerate(params)}
        self._blocks: dict[tuple[Group, str], list[int]] = {}  # (group, owner) -> its columns, in field order
        for p, i in self._columns.items():
            self._blocks.setdefault((p.group, p.owner), []).append(i)
        self._nominal = np.array(nominal)

    @property
    def size(self) -> int:
        """Number of parameters."""
        return len(self.parameters)

    def nominal(self) -> FloatArray:
        """Nominal parameter vector (URDF values, zero offsets). Shape (p,)."""
        return self._nominal.copy()

    def columns(self, group: Group) -> NDArray[np.intp]:
        """Indices of the parameters of a group. Shape (k,)."""
        return np.array([i for i, p in enumerate(self.parameters) if p.group == group], dtype=int)

    def column(self, parameter: Parameter) -> int:
        """Column of a parameter in the parameter vector.

        Raises:
            KeyError: The model has no such parameter.

        """
        return self._columns[parameter]

    def placement_columns(self, name: str) -> list[int]:
        """Columns of a placement's six parameters, in PLACEMENT_FIELDS order."""
        return list(self._blocks[Group.PLACEMENT, name])

    def contact_columns(self, frame: str) -> list[int]:
        """Columns of a contact frame's three offsets, in OFFSET_FIELDS order."""
        return list(self._blocks[Group.CONTACT, frame])

    def plane_columns(self, session: str) -> list[int]:
        """Columns of a session's plane (z, roll, pitch), in OFFSET_FIELDS order."""
        return list(self._blocks[Group.PLANE, session])

    def _placements(self, theta: FloatArray, model: ChainModel) -> dict[str, FloatArray]:
        return {name: theta[self.placement_columns(name)] for name in model.placement_names}

    def residuals(self, theta: FloatArray, contacts: Contacts) -> FloatArray:
        """Height (m), roll, pitch (rad) of each contact frame in its plane frame. Shape (n, 3)."""
        return self._evaluate(theta, contacts, jacobian=False, joints=False)[0]

    def jacobian(self, theta: FloatArray, contacts: Contacts) -> tuple[FloatArray, FloatArray]:
        """Residuals (n, 3) and their derivatives with respect to every parameter (n, 3, p)."""
        res, jac, _ = self._evaluate(theta, contacts, jacobian=True, joints=False)
        return res, jac

    def derivatives(self, theta: FloatArray, contacts: Contacts) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Residuals (n, 3), derivatives w.r.t. the parameters (n, 3, p) and the joint angles (n, 3, nj)."""
        res, jac, d_joints = self._evaluate(theta, contacts, jacobian=True, joints=True)
        assert d_joints is not None
        return res, jac, d_joints

    def _evaluate(
        self, theta: FloatArray, contacts: Contacts, jacobian: bool, joints: bool
    ) -> tuple[FloatArray, FloatArray, FloatArray | None]:
        n = len(contacts)
        res = np.zeros((n, 3))
        jac = np.zeros((n, 3, self.size if jacobian else 0))
        d_joints = np.zeros((n, 3, contacts.joints.shape[1])) if joints else None
        chains = np.array(contacts.chains)
        sessions = np.array(contacts.sessions)
        for name, model in self.chains.items():
            for session in self.sessions:
                rows = np.flatnonzero((chains == name) & (sessions == session))
                if len(rows) == 0:
                    continue
                out = self._evaluate_block(theta, model, session, contacts.joints[rows], jacobian, joints)
                res[rows] = out[0]
                if jacobian:
                    jac[rows] = out[1]
                if d_joints is not None:
                    d_joints[rows] = out[2]
        unknown = set(contacts.chains) - set(self.chains) or set(contacts.sessions) - set(self.sessions)
        if unknown:
            raise ValueError(f"contacts of chains/sessions the model does not have: {sorted(unknown)}")
        return res, jac, d_joints

    def _evaluate_block(
        self, theta: FloatArray, model: ChainModel, session: str, joints: FloatArray, jacobian: bool, by_joint: bool
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        placements = self._placements(theta, model)
        contact = theta[self.contact_columns(model.contact_frame)]
        elements, tip = model.transforms(joints, placements, contact)
        plane = offset_matrix(*theta[self.plane_columns(session)])
        plane_inv = rigid_inverse(plane)
        n = joints.shape[0]
        prefixes = [np.broadcast_to(np.eye(4), (n, 4, 4))]
        for t in elements:
            prefixes.append(prefixes[-1] @ t)
        sole_to_contact = prefixes[-1] @ tip  # (n, 4, 4)
        frames = plane_inv @ sole_to_contact
        res = tilt_measurement(frames)
        if not jacobian:
            return res, np.zeros((n, 3, 0)), np.zeros((n, 3, 0))
        jac = np.zeros((n, 3, self.size))
        d_joints = np.zeros((n, 3, joints.shape[1])) if by_joint else None
        w = plane_inv[2]  # (4,) third row: the measurement only reads row 2 of the frame
        suffix = np.broadcast_to(tip, (n, 4, 4))
        for k in range(len(elements) - 1, -1, -1):
            element = model.elements[k]
            u = w @ prefixes[k]  # (n, 4)
            d_e = element_derivatives(element, elements[k], placements[element.name])  # (n, 6, 4, 4)
            d_row = np.einsum("ni,npij,njk->npk", u, d_e, suffix)  # (n, 6, 4)
            jac[:, :, self.placement_columns(element.name)] += tilt_measurement_jacobian(frames[:, 2], d_row)
            if d_joints is not None and element.joint is not None:
                d_row = np.einsum("ni,nij,njk->nk", u, joint_derivative(element, elements[k]), suffix)[:, None]
                d_joints[:, :, element.joint] += tilt_measurement_jacobian(frames[:, 2], d_row)[:, :, 0]
            suffix = elements[k] @ suffix
        # contact offsets: tip = C_nom Off(z, roll, pitch)
        offset = _offset_derivatives(contact)  # (3, 4, 4)
        u = w @ prefixes[-1]  # (n, 4)
        d_row = np.einsum("ni,pij->npj", u, model.contact_nominal @ offset)
        jac[:, :, self.contact_columns(model.contact_frame)] += tilt_measurement_jacobian(frames[:, 2], d_row)
        # plane: frames = P^-1 T -> d frames = -P^-1 dP frames
        d_plane = _offset_derivatives(theta[self.plane_columns(session)])
        d_row = -np.einsum("i,pij,njk->npk", w, d_plane, frames)
        jac[:, :, self.plane_columns(session)] += tilt_measurement_jacobian(frames[:, 2], d_row)
        return res, jac, (d_joints if d_joints is not None else np.zeros((n, 3, 0)))


def _offset_derivatives(offset: FloatArray) -> FloatArray:
    """Derivatives of offset_matrix(z, roll, pitch) w.r.t. its three arguments. Shape (3, 4, 4)."""
    z, roll, pitch = offset
    return placement_derivatives(np.array([0.0, 0.0, z, roll, pitch, 0.0]))[2:5]
