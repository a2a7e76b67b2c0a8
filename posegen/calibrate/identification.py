"""Levenberg-Marquardt identification of base parameters with a physically sized prior.

The estimate minimises

    sum_contacts sum_c (r_c / sigma_c)^2 + sum_{free robot params} (delta_k / s_k)^2

where r = (height, roll, pitch) residuals, sigma_c the measurement noise per component
(estimated from the residuals themselves), delta_k the deviation of a free parameter
from its nominal value and s_k its prior size (``prior_length_m`` or
``prior_angle_rad``). Plane parameters have no prior: where the table is is unknown.
This is the maximum a posteriori estimate under Gaussian noise and a Gaussian prior.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from posegen.model import ContactModel, Contacts, Group, Weights, initial_planes, prior_scale
from posegen.robot import FloatArray, Indices


@dataclass(frozen=True)
class Fit:
    """An identified parameter vector."""

    theta: FloatArray  # (p,) all parameters
    free: tuple[int, ...]  # parameter indices that were estimated
    residuals: FloatArray  # (n, 3) training residuals: m, rad, rad
    iterations: int
    std: FloatArray  # (p,) posterior standard deviation (0 for fixed parameters)


def identify(
    model: ContactModel,
    contacts: Contacts,
    free: Indices,
    weights: Weights,
    theta0: FloatArray,
    max_iterations: int = 50,
) -> Fit:
    """Estimate the ``free`` parameters by Levenberg-Marquardt.

    Args:
        model: Measurement model.
        contacts: Training contacts.
        free: Parameter indices to estimate (base parameters); others stay at ``theta0``.
        weights: Noise and prior; the prior is centred on the nominal (URDF) values.
        theta0: (p,) starting point.
        max_iterations: Cap on Jacobian evaluations.

    """
    free_idx = np.array(free, dtype=int)
    noise = np.array(weights.noise)
    scale = prior_scale(model, weights)[free_idx]
    has_prior = np.isfinite(scale)
    prior_mean = model.nominal()[free_idx]

    def unpack(x: FloatArray) -> FloatArray:
        theta = theta0.copy()
        theta[free_idx] = x
        return theta

    def fun(x: FloatArray) -> FloatArray:
        r = model.residuals(unpack(x), contacts) / noise
        return np.concatenate([r.ravel(), (x - prior_mean)[has_prior] / scale[has_prior]])

    def jac(x: FloatArray) -> FloatArray:
        _, j = model.jacobian(unpack(x), contacts)
        j = (j[:, :, free_idx] / noise[None, :, None]).reshape(-1, len(free_idx))
        prior_rows = np.diag(1.0 / scale[has_prior])
        prior_j = np.zeros((int(has_prior.sum()), len(free_idx)))
        prior_j[:, has_prior] = prior_rows
        return np.vstack([j, prior_j])

    x, iterations = levenberg_marquardt(fun, jac, theta0[free_idx].copy(), max_iterations)
    theta = unpack(x)
    final_jac = jac(x)
    std = np.zeros(model.size)
    try:
        cov = np.linalg.inv(final_jac.T @ final_jac)
        std[free_idx] = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    except np.linalg.LinAlgError:
        std[free_idx] = np.nan
    return Fit(
        theta=theta,
        free=tuple(int(i) for i in free_idx),
        residuals=model.residuals(theta, contacts),
        iterations=iterations,
        std=std,
    )


def levenberg_marquardt(
    fun: Callable[[FloatArray], FloatArray],
    jac: Callable[[FloatArray], FloatArray],
    x0: FloatArray,
    max_iterations: int,
    step_tolerance: float = 1e-12,
) -> tuple[FloatArray, int]:
    """Minimise ||fun(x)||^2 by Levenberg-Marquardt (Marquardt's diagonal scaling).

    Stops when a step changes x by less than ``step_tolerance`` (relative) or lowers the
    cost (a dimensionless chi-square here) by less than 1e-10 (1 + cost).

    Returns:
        The minimiser and the number of Jacobian evaluations.

    """
    x = x0.copy()
    r = fun(x)
    cost = float(r @ r)
    damping = 1e-4
    iterations = 0
    while iterations < max_iterations:
        j = jac(x)
        iterations += 1
        jtj = j.T @ j
        grad = j.T @ r
        diag = np.maximum(np.diag(jtj), 1e-30)
        improved = False
        while damping < 1e12:
            try:
                step = np.linalg.solve(jtj + damping * np.diag(diag), -grad)
            except np.linalg.LinAlgError:
                damping *= 10.0
                continue
            r_new = fun(x + step)
            cost_new = float(r_new @ r_new)
            if cost_new < cost:
                improved = True
                break
            damping *= 10.0
        if not improved:
            break
        x = x + step
        r = r_new
        gain = cost - cost_new
        cost = cost_new
        damping = max(damping / 10.0, 1e-12)
        if np.linalg.norm(step) <= step_tolerance * (np.linalg.norm(x) + step_tolerance) or gain <= 1e-10 * (
            1.0 + cost
        ):
            break
    return x, iterations


def refit_planes(model: ContactModel, contacts: Contacts, theta: FloatArray, weights: Weights) -> FloatArray:
    """Re-fit only the plane parameters of the contacts' sessions (kinematics frozen)."""
    sessions = set(contacts.sessions)
    cols = [i for i, p in enumerate(model.parameters) if p.group == Group.PLANE and p.owner in sessions]
    start = initial_planes(model, contacts, theta)
    return identify(model, contacts, cols, weights, start).theta
