"""Settling a contact: the smallest arm and torso motion that makes it flush.

A force-controlled contact ends flush with the table. Given parameters ``theta``, each
contact's own arm and torso joints move by the smallest amount (Gauss-Newton,
minimum-norm steps) that makes its contact frame flush with its session's plane (a
point contact: its point at its tip radius above the plane); both soles stay on the
floor. Simulation (the true robot's contacts) and the structural base
parameters (contacts shaped like real ones) both settle contacts.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from posegen.errors import InfeasibleError
from posegen.model.contact_model import ContactModel, Contacts
from posegen.robot import FloatArray

CONTACT_TOLERANCE = 1e-12  # m or rad: the settled contact is exact to this
MAX_STEPS = 20
FD_STEP_RAD = 1e-7


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
        return model.residuals(theta, contacts.at(values))

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
    return contacts.at(joints), converged
