"""Simulated contacts on a perturbed "true" robot (``posegen simulate``).

The true robot is the nominal model with seeded random errors on every placement
parameter, on the contact offsets and on the table plane. For each planned posture the
force-controlled contact moves the chain's joints by the smallest amount that makes the
true contact frame flush with the true plane (Gauss-Newton, minimum-norm steps); the
encoders then read those angles plus noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from posegen.model import ContactModel, Contacts, Group, Parameter, Unit, settle_contacts
from posegen.robot import FloatArray, Scene


@dataclass(frozen=True)
class Perturbation:
    """Sizes of the simulated errors."""

    length_m: float = 2e-3  # sigma of placement length errors
    angle_rad: float = float(np.deg2rad(0.5))  # sigma of placement angle errors
    max_angle_rad: float = float(np.deg2rad(1.5))  # angle errors are clipped here
    plane_height_m: float | None = None  # true table height above the soles; None: the scene's table
    plane_tilt_rad: float = float(np.deg2rad(0.5))  # sigma of the table's roll and pitch
    encoder_noise_rad: float = 0.0  # sigma of the encoder readings' noise


def true_parameters(model: ContactModel, perturbation: Perturbation, seed: int) -> FloatArray:
    """Nominal parameters plus seeded random errors. Shape (p,)."""
    rng = np.random.default_rng(seed)
    theta = model.nominal()
    for i, p in enumerate(model.parameters):
        if p.group == Group.PLANE:
            continue
        if p.unit == Unit.LENGTH:
            theta[i] += rng.normal(0.0, perturbation.length_m)
        else:
            theta[i] += float(
                np.clip(
                    rng.normal(0.0, perturbation.angle_rad), -perturbation.max_angle_rad, perturbation.max_angle_rad
                )
            )
    height = perturbation.plane_height_m
    if height is None:
        height = float(model.scene.table_pose[2, 3])
    for session in model.sessions:
        theta[model.column(Parameter.plane(session, "z"))] = height
        for field in ("roll", "pitch"):
            theta[model.column(Parameter.plane(session, field))] = rng.normal(0.0, perturbation.plane_tilt_rad)
    return theta


def simulate(
    scene: Scene, planned: Contacts, perturbation: Perturbation, seed: int
) -> tuple[Contacts, ContactModel, FloatArray]:
    """Recorded contacts of a perturbed robot at planned postures.

    Args:
        scene: Scene of the nominal robot.
        planned: Planned postures (chains, sessions, joints).
        perturbation: Error sizes.
        seed: Seed of the errors and of the encoder noise.

    Returns:
        The recorded contacts (settled joints plus encoder noise), the model and the
        true parameter vector (p,).

    """
    model = ContactModel(scene, sorted(set(planned.chains)), sorted(set(planned.sessions)))
    theta = true_parameters(model, perturbation, seed)
    settled = settle_contacts(model, theta, planned)
    rng = np.random.default_rng([seed, 1])
    noisy = settled.joints + rng.normal(0.0, perturbation.encoder_noise_rad, settled.joints.shape)
    return Contacts(noisy, settled.chains, settled.sessions, settled.labels), model, theta
