"""The floor closure of a standing posture: where the second sole is, seen from the first.

Both soles of every recorded posture are flat on one floor and do not move within a
table session. The pose of the second sole in the first sole's frame, computed up the
first leg to the root and down the second, therefore has zero height, roll and pitch,
and x, y, yaw that are constants of the session: six equations per posture that tie the
two legs' parameters together (a second measurement kind, beside the contacts).

The legs are those of the contact model's chains whose soles are the stance's two sole
frames; both must be present.
"""

from __future__ import annotations

import numpy as np

from posegen.errors import InfeasibleError
from posegen.model.chain_pass import ChainPass, rigid_inverses, row_derivatives
from posegen.model.contact_model import ContactModel
from posegen.model.kinematics import ChainModel
from posegen.robot import FloatArray, tilt_measurement, tilt_measurement_jacobian

FLOOR_FIELDS = ("x", "y", "z", "roll", "pitch", "yaw")  # m, m, m, rad, rad, rad
SESSION_FIELDS = ("x", "y", "yaw")  # constants of a session; height, roll and pitch are zero


class FloorModel:
    """Pose of the second sole in the first sole's frame, over a contact model's parameters."""

    def __init__(self, contacts: ContactModel) -> None:
        """Take the two legs from the chains of ``contacts`` whose soles are the stance's sole frames.

        Raises:
            InfeasibleError: The model's chains do not include both soles.

        """
        self.contacts = contacts
        by_sole = {chain.elements[0].name: chain for chain in contacts.chains.values()}
        soles = contacts.scene.stance.sole_frames
        missing = [s for s in soles if s not in by_sole]
        if missing:
            raise InfeasibleError(
                f"the floor equations need a chain from each sole; no chain starts at {', '.join(missing)}"
            )
        self.legs: tuple[ChainModel, ChainModel] = (by_sole[soles[0]], by_sole[soles[1]])
        self._columns = {  # leg -> (E, 6) columns of its elements' placements, sole to root
            leg.chain: np.array([contacts.placement_columns(e.name) for e in leg.elements if e.reverse])
            for leg in self.legs
        }

    def _leg(self, chain: ChainModel, theta: FloatArray, joints: FloatArray, jacobian: bool) -> ChainPass:
        """The leg's elements from its sole up to the root, at n postures."""
        params = theta[self._columns[chain.chain]]  # (E, 6)
        return chain.pass_at(joints, params, legs_only=True, derivatives=jacobian)

    def measure(self, theta: FloatArray, joints: FloatArray) -> FloatArray:
        """x, y, z (m), roll, pitch, yaw (rad) of the second sole in the first sole's frame. Shape (n, 6)."""
        return self._evaluate(theta, joints, jacobian=False)[0]

    def measure_batch(self, thetas: FloatArray, joints: FloatArray) -> FloatArray:
        """:meth:`measure` of F parameter vectors (F, p) at joints (n, nj), or each one's own (F, n, nj). (F, n, 6)."""
        frames = self.second_sole_frames(thetas, joints)
        return _pose_measurement(frames.reshape(-1, 4, 4)).reshape(*frames.shape[:2], 6)

    def second_sole_frames(self, thetas: FloatArray, joints: FloatArray) -> FloatArray:
        """The second sole's pose (4, 4) in the first sole's frame, per parameter vector and posture. (F, n, 4, 4).

        Args:
            thetas: F parameter vectors (F, p).
            joints: Joint angles (n, nj) rad, or each parameter vector's own (F, n, nj).

        Example:
            >>> frames = FloorModel(model).second_sole_frames(model.nominal()[None], contacts.joints)
            >>> frames[0, :, 2, 3]  # the second sole's height above the first's floor, m: about 0
            array([...])

        """
        first, second = (leg.products(joints, thetas[:, self._columns[leg.chain]], legs_only=True) for leg in self.legs)
        return np.asarray(first @ rigid_inverses(second))

    def derivatives(self, theta: FloatArray, joints: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The measurement (n, 6), its derivatives w.r.t. the parameters (n, 6, p) and the joints (n, 6, nj)."""
        return self._evaluate(theta, joints, jacobian=True)

    def _evaluate(
        self, theta: FloatArray, joints: FloatArray, jacobian: bool
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        first, second = (self._leg(chain, theta, joints, jacobian) for chain in self.legs)
        up, down = first.prefixes[-1], second.prefixes[-1]  # root in each sole frame
        down_inv = rigid_inverses(down)
        frames = up @ down_inv  # (n, 4, 4) second sole in the first
        meas = _pose_measurement(frames)
        n = joints.shape[0]
        if not jacobian:
            return meas, np.zeros((n, 6, 0)), np.zeros((n, 6, 0))
        p, nj = self.contacts.size, joints.shape[1]
        d_frames = np.zeros((n, p, 4, 4))
        d_joint_frames = np.zeros((n, nj, 4, 4))
        # F = U D^-1: an element of the first leg gives dF = P dE S D^-1, one of the second -F P dE S D^-1
        for chain, state, rows in ((self.legs[0], first, np.eye(4)[:3]), (self.legs[1], second, -frames[:, :3])):
            d_place, d_joint = row_derivatives(state, rows, down_inv)  # rows 0-2 of dF: the measurement reads them
            d_frames[:, self._columns[chain.chain].ravel(), :3] += d_place
            leg_joints = [e.joint for e in chain.elements[: len(state.transforms)] if e.joint is not None]
            d_joint_frames[:, leg_joints, :3] += d_joint
        return meas, _pose_measurement_jacobian(frames, d_frames), _pose_measurement_jacobian(frames, d_joint_frames)


def _pose_measurement(frames: FloatArray) -> FloatArray:
    """x, y (m), then height, roll, pitch (tilt measurement), then yaw (rad). Shape (n, 6)."""
    tilt = tilt_measurement(frames)
    yaw = np.arctan2(frames[:, 1, 0], frames[:, 0, 0])
    return np.column_stack([frames[:, 0, 3], frames[:, 1, 3], tilt, yaw])


def _pose_measurement_jacobian(frames: FloatArray, d_frames: FloatArray) -> FloatArray:
    """Derivatives of :func:`_pose_measurement` given (n, q, 4, 4) frame derivatives. Shape (n, 6, q)."""
    n, q = d_frames.shape[:2]
    out = np.zeros((n, 6, q))
    out[:, 0] = d_frames[:, :, 0, 3]
    out[:, 1] = d_frames[:, :, 1, 3]
    out[:, 2:5] = tilt_measurement_jacobian(frames[:, 2], d_frames[:, :, 2, :])
    r00, r10 = frames[:, 0, 0][:, None], frames[:, 1, 0][:, None]
    out[:, 5] = (r00 * d_frames[:, :, 1, 0] - r10 * d_frames[:, :, 0, 0]) / (r00**2 + r10**2)
    return out
