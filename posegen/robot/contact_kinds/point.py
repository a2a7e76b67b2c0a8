"""The point contact: one fingertip or a round hand on the table; it measures the height only.

A chain declares it with ``point_frame``: a frame at the centre of the touching tip's
rounding, z away from the table at a contact, ``point_radius_m`` above it. The hand's
orientation is free within ``point_cone_deg`` of the table normal. Its contact
parameters are the point's (x, y, z) in its frame; the calibrated URDF writes the
point frame itself at its calibrated placement.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from posegen.errors import ConfigError
from posegen.robot.contact_kinds.kind import ContactKind, height_rows
from posegen.robot.geometry import FloatArray
from posegen.robot.transforms import TRANSLATION_DERIVATIVES, translation_matrix

if TYPE_CHECKING:
    from posegen.robot.chain_config import ChainConfig
    from posegen.robot.feasibility import Assessment
    from posegen.robot.scene import Scene

MAX_CONE_DEG = 90.0  # a cone this wide would let the hand lie on its side


class PointContact(ContactKind):
    """A rounded tip on the table: its centre's height above the table less the tip radius."""

    value = "point"
    frame_title = "point frame"
    required_field = "point_frame"
    group = "point"
    fields = ("x", "y", "z")
    rows = (True, False, False)
    aligned = False
    folded = False

    def declared(self, chain: ChainConfig) -> bool:
        """A chain with a point frame makes point contacts."""
        return bool(chain.point_frame)

    def check(self, chain: ChainConfig, planned: bool) -> None:
        """A point frame when planned; a cone narrower than a right angle."""
        if planned and not chain.point_frame:
            raise ConfigError(f"chains.{chain.name}.point_frame: missing (needed by contact_kind point)")
        if chain.point_cone_deg >= MAX_CONE_DEG:
            raise ConfigError(
                f"chains.{chain.name}.point_cone_deg: must be below {MAX_CONE_DEG:.0f} deg, got {chain.point_cone_deg}"
            )

    def frame(self, chain: ChainConfig) -> str:
        """The point frame."""
        return chain.point_frame

    def carried_frames(self, chain: ChainConfig) -> tuple[str, ...]:
        """The point frame, if declared."""
        return (chain.point_frame,) if chain.point_frame else ()

    def nominal_tip(self, scene: Scene, chain: ChainConfig) -> FloatArray | None:
        """The point frame in the gripper frame (the fingers locked)."""
        placement = scene.point_placements.get(chain.name)
        return None if placement is None else np.array(placement.homogeneous)

    def placement_in_gripper(self, model: pin.Model, data: pin.Data, chain: ChainConfig, q: FloatArray) -> FloatArray:
        """The model's point frame."""
        grip = data.oMf[model.getFrameId(chain.gripper_frame)]
        return np.array(grip.actInv(data.oMf[model.getFrameId(chain.point_frame)]).homogeneous)

    def lift_m(self, chain: ChainConfig) -> float:
        """The tip's centre stays its radius above the table."""
        return chain.point_radius_m

    def excess(self, assessment: Assessment, height_tol_m: float, angle_tol_rad: float) -> float:
        """Height over its tolerance, tilt over the cone."""
        return max(abs(assessment.contact_height_m) - height_tol_m, assessment.contact_tilt_rad - assessment.cone_rad)

    def detail(self, assessment: Assessment) -> str:
        """Height, tilt and cone."""
        return (
            f"height {assessment.contact_height_m:.2e} m, tilt {np.rad2deg(assessment.contact_tilt_rad):.1f} deg "
            f"(cone {np.rad2deg(assessment.cone_rad):.0f} deg)"
        )

    def tip_offset(self, params: FloatArray) -> FloatArray:
        """Trans(x, y, z)."""
        return translation_matrix(params)

    def tip_offset_derivatives(self, params: FloatArray) -> FloatArray:
        """Derivatives of the (x, y, z) translation."""
        return TRANSLATION_DERIVATIVES

    def measure(self, frames: FloatArray, chain: ChainConfig) -> FloatArray:
        """Height of the tip's centre less its radius (m), and two zero rows."""
        out = np.zeros((frames.shape[0], 3))
        out[:, 0] = frames[:, 2, 3] - chain.point_radius_m
        return out

    def measure_jacobian(self, row: FloatArray, d_row: FloatArray) -> FloatArray:
        """Derivatives of the height row only."""
        return height_rows(d_row)


POINT = PointContact()
