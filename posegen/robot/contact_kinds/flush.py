"""The flush contact: three fingertips (or a face) on the table; it measures height, roll and pitch.

posegen adds the chain's ``contact_frame`` at the fingertip ends' centroid
(:func:`contact_placement`). Its contact parameters are that frame's (z, roll, pitch)
offset in the gripper frame; the calibrated URDF folds them into the gripper frame, so
the contact frame posegen derives at load is the calibrated one.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError
from posegen.robot.contact_kinds.kind import ContactKind
from posegen.robot.geometry import FloatArray, frame_id
from posegen.robot.transforms import offset_derivatives, offset_matrix, tilt_measurement, tilt_measurement_jacobian

if TYPE_CHECKING:
    from posegen.robot.chain_config import ChainConfig
    from posegen.robot.feasibility import Assessment
    from posegen.robot.scene import Scene

FINGERTIPS = 3  # the fewest fingertip frames that make a plane


class FlushContact(ContactKind):
    """Three fingertips or a face flat on the table: the contact frame's height, roll and pitch."""

    value = "flush"
    frame_title = "contact frame"
    required_field = "fingertip_frames"
    group = "contact"
    fields = ("z", "roll", "pitch")
    rows = (True, True, True)
    aligned = True
    folded = True

    def declared(self, chain: ChainConfig) -> bool:
        """A chain with fingertip frames makes flush contacts."""
        return bool(chain.fingertip_frames)

    def check(self, chain: ChainConfig, planned: bool) -> None:
        """Three fingertips at least, when planned or declared."""
        if (planned or chain.fingertip_frames) and len(chain.fingertip_frames) < FINGERTIPS:
            raise ConfigError(f"chains.{chain.name}.fingertip_frames: a flush contact needs {FINGERTIPS} fingertips")

    def frame(self, chain: ChainConfig) -> str:
        """The contact frame posegen adds."""
        return chain.contact_frame

    def carried_frames(self, chain: ChainConfig) -> tuple[str, ...]:
        """The fingertip frames."""
        return tuple(chain.fingertip_frames)

    def nominal_tip(self, scene: Scene, chain: ChainConfig) -> FloatArray | None:
        """The contact frame in the gripper frame (the fingers locked)."""
        placement = scene.contact_placements.get(chain.name)
        return None if placement is None else np.array(placement.homogeneous)

    def placement_in_gripper(self, model: pin.Model, data: pin.Data, chain: ChainConfig, q: FloatArray) -> FloatArray:
        """The contact frame derived from the model's fingertips at q."""
        return np.array(contact_placement(model, chain, q).homogeneous)

    def lift_m(self, chain: ChainConfig) -> float:
        """The contact frame lies on the table."""
        return 0.0

    def excess(self, assessment: Assessment, height_tol_m: float, angle_tol_rad: float) -> float:
        """Height, roll and pitch each over their tolerance."""
        return max(
            abs(assessment.contact_height_m) - height_tol_m,
            abs(assessment.contact_roll_rad) - angle_tol_rad,
            abs(assessment.contact_pitch_rad) - angle_tol_rad,
        )

    def detail(self, assessment: Assessment) -> str:
        """Height, roll and pitch."""
        return (
            f"height {assessment.contact_height_m:.2e} m, roll {assessment.contact_roll_rad:.2e} rad, "
            f"pitch {assessment.contact_pitch_rad:.2e} rad"
        )

    def tip_offset(self, params: FloatArray) -> FloatArray:
        """Trans(0, 0, z) Rot_rpy(roll, pitch, 0)."""
        return offset_matrix(*params)

    def tip_offset_derivatives(self, params: FloatArray) -> FloatArray:
        """Derivatives of the (z, roll, pitch) offset."""
        return offset_derivatives(params)

    def measure(self, frames: FloatArray, chain: ChainConfig) -> FloatArray:
        """Height (m), roll and pitch (rad) of the contact frame."""
        return tilt_measurement(frames)

    def measure_jacobian(self, row: FloatArray, d_row: FloatArray) -> FloatArray:
        """Derivatives of height, roll and pitch."""
        return tilt_measurement_jacobian(row, d_row)


FLUSH = FlushContact()


def contact_placement(model: pin.Model, chain: ChainConfig, q: FloatArray | None = None) -> pin.SE3:
    """Placement of a chain's contact frame in its gripper frame.

    Origin: centroid of the fingertip ends (each ``fingertip_length_m`` beyond its link
    origin, against the normal). z: normal of the fingertip plane, pointing to the side
    of the gripper frame origin. x: the gripper frame's x projected on the plane.

    Args:
        model: The robot model.
        chain: The chain.
        q: Configuration the fingertips are read at (locked finger joints matter);
            None for the neutral one. Shape (nq,).

    """
    data = model.createData()
    pin.framesForwardKinematics(model, data, pin.neutral(model) if q is None else q)
    grip = data.oMf[frame_id(model, chain.gripper_frame)]
    tips = np.array([grip.actInv(data.oMf[frame_id(model, f)]).translation for f in chain.fingertip_frames])  # (n, 3)
    centroid = tips.mean(axis=0)
    normal = np.linalg.svd(tips - centroid)[2][-1]
    if normal @ (-centroid) < 0:
        normal = -normal
    x_axis = np.array([1.0, 0.0, 0.0]) - normal[0] * normal
    if np.linalg.norm(x_axis) < 1e-6:
        x_axis = np.array([0.0, 1.0, 0.0]) - normal[1] * normal
    x_axis /= np.linalg.norm(x_axis)
    rotation = np.column_stack([x_axis, np.cross(normal, x_axis), normal])
    return pin.SE3(rotation, centroid - chain.fingertip_length_m * normal)
