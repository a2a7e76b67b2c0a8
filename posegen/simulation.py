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
from numpy.typing import NDArray

from posegen.contact_model import ContactModel, Contacts, Group, Unit
from posegen.errors import InfeasibleError
from posegen.geometry import FloatArray
from posegen.scene import Scene

CONTACT_TOLERANCE = 1e-12  # m or rad: the true contact is exact to this
MAX_STEPS = 20
FD_STEP_RAD = 1e-7


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
        theta[model.index[f"plane@{session}.z"]] = height
        for field in ("roll", "pitch"):
            theta[model.index[f"plane@{session}.{field}"]] = rng.normal(0.0, perturbation.plane_tilt_rad)
    return theta


def settle_contacts(model: ContactModel, theta: FloatArray, contacts: Contacts) -> Contacts:
    """Move each contact's arm and torso joints minimally until it is flush under ``theta``.

    Each contact moves only the joints of its own chain that are not leg joints: both
    soles stay on the floor, as when a force-controlled contact settles.

    Raises:
        InfeasibleError: A contact cannot be made flush (the plane is out of reach).

    """
    settled, converged = settle(model, theta, contacts)
    if not np.all(converged):
        worst = int(np.flatnonzero(~converged)[0])
        raise InfeasibleError(f"simulated contact {contacts.labels[worst]!r} does not settle on the true plane")
    return settled


def settle(model: ContactModel, theta: FloatArray, contacts: Contacts) -> tuple[Contacts, NDArray[np.bool_]]:
    """Batch Gauss-Newton of :func:`settle_contacts`; also returns which contacts converged (n,)."""
    scene = model.scene
    legs = set(scene.stance_leg_joints())
    own_joints = {name: set(chain.joint_indices) - legs for name, chain in model.chains.items()}
    cols = sorted(set().union(*own_joints.values()))
    own = {name: [k for k, col in enumerate(cols) if col in joints] for name, joints in own_joints.items()}
    joints = contacts.joints.copy()

    def residuals(values: FloatArray) -> FloatArray:
        return model.residuals(theta, Contacts(values, contacts.chains, contacts.sessions, contacts.labels))

    res = residuals(joints)  # (n, 3)
    for _ in range(MAX_STEPS):
        if np.max(np.abs(res)) < CONTACT_TOLERANCE:
            break
        jac = np.zeros((len(contacts), 3, len(cols)))
        for k, col in enumerate(cols):
            shifted = joints.copy()
            shifted[:, col] += FD_STEP_RAD
            jac[:, :, k] = (residuals(shifted) - res) / FD_STEP_RAD
        for i, chain in enumerate(contacts.chains):
            step = np.linalg.lstsq(jac[i][:, own[chain]], -res[i], rcond=None)[0]  # minimum-norm correction
            joints[i, [cols[k] for k in own[chain]]] += step
        res = residuals(joints)
    # No limit check: like the real robot's, a settled joint may read a little past the URDF limit.
    converged = np.all(np.abs(res) < 1e-9, axis=1)
    return Contacts(joints, contacts.chains, contacts.sessions, contacts.labels), converged


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
