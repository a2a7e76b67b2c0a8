"""The plane-constrained measurement model of one or more chains and table sessions.

Parameters (a flat vector, named): every placement of every chain (shared placements,
such as the torso's, appear once), each chain's contact parameters for each contact
kind it makes (the kind's ``fields``: a flush contact frame's z, roll, pitch offsets; a
contact point's x, y, z), and one plane per table session. Residuals of a set of
contacts: (n, 3) per contact, what its kind measures of its tip frame in its session's
plane frame (:class:`posegen.robot.ContactKind`): height (m), roll, pitch (rad) of a
flush contact frame, or height of a point above the plane less its tip radius and two
zero rows (:mod:`posegen.model.contact_rows` says which rows are real). The zero rows
keep one layout for every design formula: their Jacobian is zero too. Nothing here
names a kind: the model asks each kind.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from dataclasses import field as dataclass_field

import numpy as np
from numpy.typing import NDArray

from posegen.model.chain_pass import placement_stack, rigid_inverses, row_derivatives
from posegen.model.kinematics import ChainModel
from posegen.model.parameters import OFFSET_FIELDS, PLACEMENT_FIELDS, Group, Parameter
from posegen.robot import DEFAULT_KIND, ContactKind, FloatArray, Indices, Scene, offset_derivatives, offset_matrix


@dataclass(frozen=True)
class Contacts:
    """Recorded (or simulated) contacts, flush or point."""

    joints: FloatArray  # (n, nj) rad, in the scene's joint order
    chains: tuple[str, ...]  # chain in contact, per contact
    sessions: tuple[str, ...]  # table session (one plane each), per contact
    labels: tuple[str, ...]  # e.g. target spot or source row, per contact
    kinds: tuple[ContactKind, ...] = dataclass_field(
        default=()
    )  # per contact; () means every contact is of DEFAULT_KIND

    def __post_init__(self) -> None:
        if not self.kinds:
            object.__setattr__(self, "kinds", (DEFAULT_KIND,) * len(self.chains))
        if len(self.kinds) != len(self.chains):
            raise ValueError(f"{len(self.kinds)} contact kinds for {len(self.chains)} contacts")

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
            kinds=tuple(self.kinds[i] for i in idx),
        )

    def concat(self, other: Contacts) -> Contacts:
        """These contacts followed by ``other``."""
        return Contacts(
            joints=np.vstack([self.joints, other.joints]),
            chains=self.chains + other.chains,
            sessions=self.sessions + other.sessions,
            labels=self.labels + other.labels,
            kinds=self.kinds + other.kinds,
        )

    def at(self, joints: FloatArray) -> Contacts:
        """The same contacts at other joint angles (n, nj) (not copied)."""
        return Contacts(joints, self.chains, self.sessions, self.labels, self.kinds)

    def kinds_by_chain(self) -> dict[str, tuple[ContactKind, ...]]:
        """Chain -> the contact kinds its rows make (in their names' order)."""
        out: dict[str, set[ContactKind]] = {}
        for chain, kind in zip(self.chains, self.kinds, strict=True):
            out.setdefault(chain, set()).add(kind)
        return {c: tuple(sorted(kinds)) for c, kinds in out.items()}


def planned_kinds(scene: Scene, chains: Sequence[str]) -> tuple[ContactKind, ...]:
    """The kind of contact ``pool`` plans for each chain (its ``contact_kind``), per contact."""
    return tuple(scene.chain(c).contact_kind for c in chains)


Block = tuple[ChainModel, str, ContactKind, NDArray[np.intp]]  # a chain, session and kind, and its contacts' rows
GROUPS_REMEMBERED = 256  # sets of contacts whose grouping by chain, session and kind a model remembers


class ContactModel:
    """Measurement model of contacts of some chains at some table sessions."""

    def __init__(
        self,
        scene: Scene,
        chains: Sequence[str],
        sessions: Sequence[str],
        kinds: Mapping[str, Sequence[ContactKind]] | None = None,
    ) -> None:
        """Build the model.

        Args:
            scene: Scene.
            chains: Chains measured.
            sessions: Table sessions (one plane each).
            kinds: Chain -> the contact kinds it makes (contact parameters for each);
                a chain not named makes the kind ``pool`` plans for it.

        Raises:
            ConfigError: A chain declares no contact of a kind it is given.

        """
        self.scene = scene
        given = dict(kinds or {})
        self.kinds = {  # chain -> its contact kinds, in their names' order
            c: tuple(sorted(set(given.get(c, (scene.chain(c).contact_kind,))))) for c in dict.fromkeys(chains)
        }
        self.chains = {c: ChainModel(scene, c, self.kinds[c]) for c in self.kinds}
        self.sessions = tuple(dict.fromkeys(sessions))
        for name, model in self.chains.items():
            for kind in self.kinds[name]:
                model.tip_nominal(kind)  # raises when the chain declares no such contact
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
        for name, model in self.chains.items():
            for kind in self.kinds[name]:
                params.extend(Parameter(Group(kind.group), model.frame(kind), f) for f in kind.fields)
        if len(set(params)) < len(params):
            raise ValueError(f"contact kinds of one chain name the same parameters (group and frame): {self.kinds}")
        nominal.extend([0.0] * (len(params) - len(nominal)))
        for session in self.sessions:
            params.extend(Parameter.plane(session, f) for f in OFFSET_FIELDS)
            nominal.extend([0.0] * len(OFFSET_FIELDS))
        self.parameters = tuple(params)
        self.index = {p.name: i for i, p in enumerate(params)}  # parameter name -> column
        self._columns = {p: i for i, p in enumerate(params)}
        self._blocks: dict[tuple[Group, str], list[int]] = {}  # (group, owner) -> its columns, in field order
        for p, i in self._columns.items():
            self._blocks.setdefault((p.group, p.owner), []).append(i)
        self._nominal = np.array(nominal)
        self._groups: dict[tuple[object, ...], list[Block]] = {}  # contacts -> their blocks
        self._chain_columns = {  # chain -> (E, 6) columns of its elements' placements, in chain order
            name: np.array([self.placement_columns(e.name) for e in chain.elements])
            for name, chain in self.chains.items()
        }

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

    def point_columns(self, frame: str) -> list[int]:
        """Columns of a contact point's three coordinates, in POINT_FIELDS order."""
        return list(self._blocks[Group.POINT, frame])

    def tip_columns(self, chain: str, kind: ContactKind) -> list[int]:
        """Columns of a chain's contact parameters of one kind, in the kind's ``fields`` order."""
        return list(self._blocks[Group(kind.group), self.chains[chain].frame(kind)])

    def plane_columns(self, session: str) -> list[int]:
        """Columns of a session's plane (z, roll, pitch), in OFFSET_FIELDS order."""
        return list(self._blocks[Group.PLANE, session])

    def _placements(self, theta: FloatArray, model: ChainModel) -> dict[str, FloatArray]:
        return {name: theta[self.placement_columns(name)] for name in model.placement_names}

    def residuals(self, theta: FloatArray, contacts: Contacts) -> FloatArray:
        """Height (m), roll, pitch (rad) of each contact in its plane frame (a point's: height, 0, 0). Shape (n, 3)."""
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

    def residuals_batch(self, thetas: FloatArray, contacts: Contacts, joints: FloatArray | None = None) -> FloatArray:
        """:meth:`residuals` of F parameter vectors (F, p) at once. Shape (F, n, 3).

        ``joints`` (F, n, nj): each vector's own joint angles (a compliant model's deflection);
        None: the contacts' joints for every vector.

        Example:
            >>> model.residuals_batch(np.stack([theta, other]), contacts)[1]  # == model.residuals(other, contacts)

        """
        sets, n = thetas.shape[0], len(contacts)
        res = np.zeros((sets, n, 3))
        angles = contacts.joints if joints is None else joints
        for model, session, kind, rows in self._blocks_of(contacts):
            product = model.products(angles[..., rows, :], thetas[:, self._chain_columns[model.chain]])  # (F, m, 4, 4)
            tips = np.array([model.tip(c, kind) for c in thetas[:, self.tip_columns(model.chain, kind)]])  # (F, 4, 4)
            plane = np.zeros((sets, 6))
            plane[:, 2:5] = thetas[:, self.plane_columns(session)]  # offset_matrix(z, roll, pitch) as a placement
            planes_inv = placement_stack(plane, derivatives=False).inverses  # (F, 4, 4)
            frames = planes_inv[:, None] @ product @ tips[:, None]
            res[:, rows] = kind.measure(frames.reshape(-1, 4, 4), model.config).reshape(sets, len(rows), 3)
        return res

    def _evaluate(
        self, theta: FloatArray, contacts: Contacts, jacobian: bool, joints: bool
    ) -> tuple[FloatArray, FloatArray, FloatArray | None]:
        n = len(contacts)
        res = np.zeros((n, 3))
        jac = np.zeros((n, 3, self.size if jacobian else 0))
        d_joints = np.zeros((n, 3, contacts.joints.shape[1])) if joints else None
        for model, session, kind, rows in self._blocks_of(contacts):
            out = self._evaluate_block(theta, model, session, kind, contacts.joints[rows], jacobian, joints)
            res[rows] = out[0]
            if jacobian:
                jac[rows] = out[1]
            if d_joints is not None:
                d_joints[rows] = out[2]
        return res, jac, d_joints

    def _blocks_of(self, contacts: Contacts) -> list[Block]:
        """The contacts grouped by chain, kind and session: each group's rows (remembered: fits ask again and again).

        Raises:
            ValueError: Contacts of a chain, session or kind the model does not have.

        """
        key = (contacts.chains, contacts.sessions, contacts.kinds)
        found = self._groups.get(key)
        if found is not None:
            return found
        unknown = set(contacts.chains) - set(self.chains) or set(contacts.sessions) - set(self.sessions)
        if unknown:
            raise ValueError(f"contacts of chains/sessions the model does not have: {sorted(unknown)}")
        chains = np.array(contacts.chains)
        sessions = np.array(contacts.sessions)
        kinds = np.array([k.value for k in contacts.kinds])
        found = []
        for name, model in self.chains.items():
            for kind in sorted(set(contacts.kinds)):
                mine = (chains == name) & (kinds == kind.value)
                if not mine.any():
                    continue
                if kind not in self.kinds[name]:
                    raise ValueError(f"{kind.value} contacts of chain '{name}': the model has no such contact")
                for session in self.sessions:
                    rows = np.flatnonzero(mine & (sessions == session))
                    if len(rows):
                        found.append((model, session, kind, rows))
        if len(self._groups) >= GROUPS_REMEMBERED:
            self._groups.clear()
        self._groups[key] = found
        return found

    def __getstate__(self) -> dict[str, object]:
        state = dict(self.__dict__)
        state["_groups"] = {}  # a cache, not state: not sent to worker processes
        return state

    def _evaluate_block(
        self,
        theta: FloatArray,
        model: ChainModel,
        session: str,
        kind: ContactKind,
        joints: FloatArray,
        jacobian: bool,
        by_joint: bool,
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        tip_columns = self.tip_columns(model.chain, kind)
        contact = theta[tip_columns]
        state = model.pass_at(joints, theta[self._chain_columns[model.chain]], derivatives=jacobian)
        tip = model.tip(contact, kind)
        plane = offset_matrix(*theta[self.plane_columns(session)])
        plane_inv = rigid_inverses(plane)
        n = joints.shape[0]
        frames = plane_inv @ (state.prefixes[-1] @ tip)  # (n, 4, 4) tip frames in the plane frame
        res = kind.measure(frames, model.config)
        if not jacobian:
            return res, np.zeros((n, 3, 0)), np.zeros((n, 3, 0))
        jac = np.zeros((n, 3, self.size))
        w = plane_inv[2]  # (4,) third row: the measurement only reads row 2 of the frame
        d_place, d_joint = row_derivatives(state, plane_inv[2:3], tip)
        # contact parameters: tip = C_nom Off(contact), the kind's offset (flush: z, roll, pitch; point: x, y, z)
        offset = kind.tip_offset_derivatives(contact)  # (m, 4, 4)
        u = w @ state.prefixes[-1]  # (n, 4)
        d_tip = np.swapaxes(u @ (model.tip_nominal(kind) @ offset), 0, 1)  # (n, m, 4)
        # plane: frames = P^-1 T -> d frames = -P^-1 dP frames
        d_plane = -((w @ offset_derivatives(theta[self.plane_columns(session)]))[None] @ frames)  # (n, 3, 4)
        # the kind measures each parameter's derivative on its own: one call for all of them
        parts = [d_place[:, :, 0], d_tip, d_plane, *([d_joint[:, :, 0]] if by_joint else [])]
        ends = np.cumsum([part.shape[1] for part in parts])
        measured = np.split(kind.measure_jacobian(frames[:, 2], np.concatenate(parts, axis=1)), ends[:-1], axis=2)
        jac[:, :, self._chain_columns[model.chain].ravel()] = measured[0]
        jac[:, :, tip_columns] += measured[1]
        jac[:, :, self.plane_columns(session)] += measured[2]
        d_joints = None
        if by_joint:
            d_joints = np.zeros((n, 3, joints.shape[1]))
            d_joints[:, :, model.joint_indices] = measured[3]
        return res, jac, (d_joints if d_joints is not None else np.zeros((n, 3, 0)))
