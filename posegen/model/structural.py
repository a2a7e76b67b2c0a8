"""Structural base parameters: what real contacts can identify, whatever their number.

The regressor's rank depends on the shape of the postures, so it is evaluated at
seeded random postures shaped like real contacts (both soles on the floor, every
contact flush at one table height per session) around the given ones, and reduced by
:func:`posegen.model.identifiability.base_parameters` (planes first). Selection builds
its design and calibration its fit on these base parameters.
"""

from __future__ import annotations

import numpy as np

from posegen.errors import InfeasibleError
from posegen.model.contact_model import ContactModel, Contacts
from posegen.model.floor_model import FloorModel
from posegen.model.identifiability import BaseParameters, base_parameters
from posegen.model.parameters import Group
from posegen.model.planes import initial_planes, level_planes
from posegen.model.settle import settle
from posegen.model.weights import DEFAULT_NOISE, UNIT_PRIOR_LENGTH_M, prior_scale, weights_for
from posegen.robot import ContactKind, FloatArray

STRUCTURAL_POSTURES = 100  # generated per (chain, session, contact kind)


def structural_base(
    model: ContactModel,
    contacts: Contacts,
    noise: tuple[float, float, float] = DEFAULT_NOISE,
    postures: int = STRUCTURAL_POSTURES,
    seed: int = 0,
    floor_sigma: tuple[float, ...] | None = None,
) -> BaseParameters:
    """Base parameters of the (chain, session, contact kind) triples present in ``contacts``.

    Args:
        model: Measurement model.
        contacts: Contacts whose (chain, session, kind) triples, joints and heights the
            regressor's postures are drawn around.
        noise: Measurement noise (m, rad, rad) scaling the regressor's rows.
        postures: Postures generated per (chain, session, kind) triple.
        seed: Seed of the generated postures.
        floor_sigma: With the floor equations (noise of x, y, z in m, roll, pitch, yaw in
            rad): their rows join the regressor, x, y and yaw less their session's mean
            (which eliminates the session's constants). None: contacts only.

    """
    return base_at(model, level_postures(model, contacts, postures, seed), noise, floor_sigma)


def base_at(
    model: ContactModel,
    postures: Contacts,
    noise: tuple[float, float, float] = DEFAULT_NOISE,
    floor_sigma: tuple[float, ...] | None = None,
) -> BaseParameters:
    """Base parameters of the regressor at given postures (see :func:`structural_base`)."""
    theta = initial_planes(model, postures, model.nominal())
    _, jac = model.jacobian(theta, postures)
    sigma = np.array(noise)
    regressor = (jac / sigma[None, :, None]).reshape(-1, model.size)
    if floor_sigma is not None:
        _, floor_jac, _ = FloorModel(model).derivatives(theta, postures.joints)  # (n, 6, p)
        sessions = np.array(postures.sessions)
        for session in set(postures.sessions):
            rows = sessions == session
            floor_jac[np.ix_(rows, [0, 1, 5])] -= floor_jac[rows][:, [0, 1, 5]].mean(axis=0)
        floor_rows = (floor_jac / np.array(floor_sigma)[None, :, None]).reshape(-1, model.size)
        regressor = np.vstack([regressor, floor_rows])
    scale = prior_scale(model, weights_for(1.0, noise))
    scale[~np.isfinite(scale)] = UNIT_PRIOR_LENGTH_M
    planes = model.columns(Group.PLANE)
    robot = np.concatenate([model.columns(Group.PLACEMENT), model.columns(Group.CONTACT), model.columns(Group.POINT)])
    return base_parameters(regressor, scale, [planes, robot])


LEG_SPREAD_RAD = 0.3  # legs perturbed by up to this in level_postures


def level_postures(model: ContactModel, contacts: Contacts, n: int, seed: int) -> Contacts:
    """Random standing contacts of each (chain, session, kind) of ``contacts``.

    Shaped like real ones, because the regressor's rank depends on it: both soles on
    the floor (the stance closure ties the two legs), and every contact flush with a
    level plane (a point contact: its point on it, the hand free to turn, as a point
    contact's hand is) at its session's mean contact height (one height per session removes
    combinations that varying heights would show). Each is a training contact with
    every joint perturbed at random (legs by up to 0.3 rad, the rest by up to 0.5 rad),
    the second leg closed onto its sole and the contact settled by the smallest arm and
    torso motion. A robot whose leg limits leave no room to close a perturbed stance
    (legs that stand only straight) gets its legs unperturbed.
    """
    scene = model.scene
    rng = np.random.default_rng(seed)
    legs = scene.stance_leg_joints()
    theta = level_planes(model, initial_planes(model, contacts, model.nominal()))  # at the measured heights
    keys = list(zip(contacts.chains, contacts.sessions, contacts.kinds, strict=True))
    parts: list[Contacts] = []
    for chain, session, kind in sorted(set(keys)):
        seeds = contacts.joints[[i for i, key in enumerate(keys) if key == (chain, session, kind)]]
        for leg_spread in (LEG_SPREAD_RAD, 0.0):
            spread = np.full(len(scene.joint_names), 0.5)
            spread[legs] = leg_spread
            found = _perturbed(model, theta, seeds, (chain, session, kind), spread, n, rng, parts)
            if found >= n:
                break
        else:
            raise InfeasibleError(f"cannot generate standing contacts like those of chain '{chain}'")
    out = parts[0]
    for part in parts[1:]:
        out = out.concat(part)
    return out


def _perturbed(
    model: ContactModel,
    theta: FloatArray,
    seeds: FloatArray,
    key: tuple[str, str, ContactKind],
    spread: FloatArray,
    n: int,
    rng: np.random.Generator,
    parts: list[Contacts],
) -> int:
    """Append to ``parts`` up to ``n`` settled perturbations of ``seeds`` (joints, (s, nj)); how many were."""
    scene = model.scene
    chain, session, kind = key
    found = 0
    for _attempt in range(50):
        samples = []
        for _ in range(2 * (n - found)):
            base = seeds[rng.integers(len(seeds))]
            sample = np.clip(base + rng.uniform(-spread, spread), scene.lower, scene.upper)
            closed = scene.close_stance(sample)
            if closed is not None:
                samples.append(closed)
        if not samples:
            continue
        m = len(samples)
        batch = Contacts(np.array(samples), (chain,) * m, (session,) * m, ("",) * m, (kind,) * m)
        settled, converged = settle(model, theta, batch)
        keep = np.flatnonzero(converged)[: n - found]
        parts.append(settled.subset(keep))
        found += len(keep)
        if found >= n:
            break
    return found
