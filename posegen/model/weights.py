"""How millimetres weigh against degrees: measurement noise and prior sizes.

Shared by the design of experiments (:mod:`posegen.select`), which scales each
posture's regressor by the noise, and by identification (:mod:`posegen.calibrate`),
which also puts a prior of size ``kappa`` x (1 mm, 0.1 deg) on every robot parameter.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from posegen.model.contact_model import ContactModel
from posegen.model.parameters import Group, Unit
from posegen.robot import FloatArray

UNIT_PRIOR_LENGTH_M = 1e-3
UNIT_PRIOR_ANGLE_RAD = float(np.deg2rad(0.1))
DEFAULT_NOISE = (1e-3, UNIT_PRIOR_ANGLE_RAD, UNIT_PRIOR_ANGLE_RAD)  # sigma of height (m), roll, pitch (rad)
DEFAULT_FLOOR_NOISE = (1e-4, 1e-4, 1e-4, float(np.deg2rad(0.01)), float(np.deg2rad(0.01)), float(np.deg2rad(0.01)))
# sigma of the floor rows (second sole's x, y, height in m; roll, pitch, yaw in rad) before they are estimated
NOISE_FLOOR = (1e-5, float(np.deg2rad(1e-3)), float(np.deg2rad(1e-3)))  # no contact is known better


@dataclass(frozen=True)
class Weights:
    """Measurement noise and prior sizes."""

    noise: tuple[float, float, float]  # sigma of height (m), roll (rad), pitch (rad)
    prior_length_m: float  # prior sigma of a length parameter's deviation
    prior_angle_rad: float  # prior sigma of an angle parameter's deviation


def weights_for(kappa: float, noise: Sequence[float] | FloatArray) -> Weights:
    """Weights with a prior of size kappa x (1 mm, 0.1 deg)."""
    return Weights(
        noise=(float(noise[0]), float(noise[1]), float(noise[2])),
        prior_length_m=kappa * UNIT_PRIOR_LENGTH_M,
        prior_angle_rad=kappa * UNIT_PRIOR_ANGLE_RAD,
    )


def prior_scale(model: ContactModel, weights: Weights) -> FloatArray:
    """Prior sigma per parameter (inf for planes: no prior). Shape (p,)."""
    scale = np.array(
        [weights.prior_length_m if p.unit == Unit.LENGTH else weights.prior_angle_rad for p in model.parameters]
    )
    scale[model.columns(Group.PLANE)] = np.inf
    return scale
