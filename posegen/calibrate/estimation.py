"""Maximum a posteriori estimation of a calibration model, and of its measurement noise.

The estimate minimises, over the free directions delta of the kind basis
(x = x_nominal + B delta; held directions stay at the URDF)::

    sum_i w_i [ sum_c (r_ic / sigma_c)^2 + sum_f (s_if / tau_f)^2 ] + sum_k (delta_k / s_k)^2

with r the contact residuals (height, roll, pitch), s the floor residuals (used only
when the spec says so), sigma and tau their noise per component, s_k the prior sigma
of each free direction (none on planes and floor constants) and w_i a weight per
posture, 1 except while screening for bad rows.

The noise of each component is the residual RMS corrected for the degrees of freedom
the fit used (RSS / (m - trace of the hat matrix over that component's rows)): an
unbiased estimate of the measurement noise even when the fit is close to interpolating,
which the training RMS is not. m counts the rows measured: a point contact measures a
height (the same quantity as a flush contact's, one sigma for both) and no roll or
pitch, whose rows are zero in residual and Jacobian alike; with no flush contact the
roll and pitch sigmas keep their values.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from posegen.model import NOISE_FLOOR, CalibrationModel, Evaluations, Kind, Observations, Spec, row_mask
from posegen.robot import FloatArray

FLOOR_NOISE_FLOOR = (1e-5, 1e-5, 1e-5, float(np.deg2rad(1e-3)), float(np.deg2rad(1e-3)), float(np.deg2rad(1e-3)))


@dataclass(frozen=True)
class Noise:
    """Measurement noise (sigma) per component of each measurement kind."""

    contact: tuple[float, float, float]  # height m, roll rad, pitch rad
    floor: tuple[float, float, float, float, float, float]  # x, y, z m; roll, pitch, yaw rad

    @classmethod
    def of(cls, contact: FloatArray, floor: FloatArray) -> Noise:
        """From arrays, bounded below by what no measurement is known better than."""
        c = np.maximum(contact, NOISE_FLOOR)
        f = np.maximum(floor, FLOOR_NOISE_FLOOR)
        return cls((float(c[0]), float(c[1]), float(c[2])), tuple(float(v) for v in f))  # type: ignore[arg-type]


@dataclass(frozen=True)
class Estimate:
    """A fitted calibration model."""

    x: FloatArray  # (nx,) parameters
    delta: FloatArray  # (nx,) deviations along the directions
    noise: Noise
    iterations: int
    std: FloatArray  # (nx,) posterior sigma along each direction, 0 when held
    rounds: tuple[FloatArray, ...] = ()  # (nx,) x after each fit of :func:`estimate`, when every one converged


def levenberg_marquardt(
    fun: Callable[[FloatArray], FloatArray],
    jac: Callable[[FloatArray], FloatArray],
    x0: FloatArray,
    max_iterations: int,
    step_tolerance: float = 1e-12,
) -> tuple[FloatArray, int]:
    """Minimise ||fun(x)||^2 by Levenberg-Marquardt (Marquardt's diagonal scaling).

    Stops when a step changes x by less than ``step_tolerance`` (relative) or lowers the
    cost (a dimensionless chi-square here) by less than 1e-7 (1 + cost): a thousandth of a unit of
    chi-square per thousand, far below what changes a prediction.

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
        if np.linalg.norm(step) <= step_tolerance * (np.linalg.norm(x) + step_tolerance) or gain <= 1e-7 * (1.0 + cost):
            break
    return x, iterations


def _problem(
    model: CalibrationModel,
    observations: Observations,
    spec: Spec,
    noise: Noise,
    fixed: FloatArray,
    weights: FloatArray,
    evaluations: Evaluations | None = None,
) -> tuple[Callable[[FloatArray], FloatArray], Callable[[FloatArray], FloatArray]]:
    """Whitened residual and Jacobian of the free deviations (data rows, then prior rows).

    ``evaluations``: the model's evaluations at ``observations`` to ask (its remembered
    ones reused); None: the model is evaluated at each call.
    """
    evaluate = _evaluations_of(model, observations, evaluations)
    free = np.array(spec.free, dtype=int)
    sd = spec.prior_sd[free]
    prior = np.isfinite(sd)
    sigma_c = np.array(noise.contact)
    sigma_f = np.array(noise.floor)
    root = np.sqrt(weights)[:, None]  # (n, 1)
    project = projection(model.basis[:, free])

    def x_of(values: FloatArray) -> FloatArray:
        delta = fixed.copy()
        delta[free] = values
        return model.x_of(delta)

    def stack(contact: FloatArray, floor: FloatArray, values: FloatArray) -> FloatArray:
        parts = [(contact / sigma_c * root).ravel()]
        if spec.floor:
            parts.append((floor / sigma_f * root).ravel())
        parts.append(values[prior] / sd[prior])
        return np.concatenate(parts)

    def fun(values: FloatArray) -> FloatArray:
        out = evaluate.evaluate(x_of(values), floor=spec.floor)
        return stack(out.contact, out.floor, values)

    def jac(values: FloatArray) -> FloatArray:
        out = evaluate.evaluate(x_of(values), jacobian=True, floor=spec.floor)
        rows = [project((out.contact_jacobian / sigma_c[None, :, None]) * root[:, :, None]).reshape(-1, len(free))]
        if spec.floor:
            whitened = (out.floor_jacobian / sigma_f[None, :, None]) * root[:, :, None]
            rows.append(project(whitened).reshape(-1, len(free)))
        rows.append(np.diag(1.0 / sd)[prior])
        return np.vstack(rows)

    return fun, jac


def _evaluations_of(
    model: CalibrationModel, observations: Observations, evaluations: Evaluations | None
) -> Evaluations:
    """``evaluations`` (checked to be of ``model`` at ``observations``), or the model evaluated afresh (None).

    Raises:
        ValueError: ``evaluations`` are of other observations, or of another model.

    """
    if evaluations is None:
        return Evaluations(model, observations, remembered=0)
    if evaluations.observations is not observations or evaluations.model is not model:
        raise ValueError("evaluations are of other observations than the ones given (or of another model)")
    return evaluations


def projection(basis: FloatArray) -> Callable[[FloatArray], FloatArray]:
    """``J -> J @ basis`` for derivatives J (..., nx) along the columns of ``basis`` (nx, f).

    The kind basis is a signed selection (one entry, +-1, per column): then its columns
    are picked, not multiplied (the same numbers as the product: each sum has one term).
    """
    nonzero = basis != 0.0
    rows = np.argmax(nonzero, axis=0)
    signs = basis[rows, np.arange(basis.shape[1])]
    if not (np.all(nonzero.sum(axis=0) == 1) and np.all(np.abs(signs) == 1.0)):
        return lambda jacobian: np.asarray(jacobian @ basis)
    # + 0.0: a product's -0 is the sum's +0
    return lambda jacobian: np.asarray(jacobian[..., rows] * signs + 0.0)


def fit(
    model: CalibrationModel,
    observations: Observations,
    spec: Spec,
    noise: Noise,
    start: FloatArray,
    max_iterations: int = 50,
    weights: FloatArray | None = None,
    evaluations: Evaluations | None = None,
) -> tuple[FloatArray, int]:
    """Deviations (nx,) of the MAP estimate at a given noise, and the Jacobian evaluations used.

    Args:
        model: Calibration model.
        observations: The postures fitted.
        spec: Free directions, prior, floor equations or not.
        noise: Measurement noise.
        start: (nx,) starting parameters; directions that are not free keep their values.
        max_iterations: Cap on Levenberg-Marquardt iterations.
        weights: (n,) weight of each posture (robust screening); None: all 1.
        evaluations: The model's evaluations at ``observations`` (:class:`Evaluations`),
            shared with the fits and noise estimates before and after this one; None:
            evaluated afresh.

    """
    free = np.array(spec.free, dtype=int)
    fixed = model.delta_of(start)
    w = np.ones(len(observations)) if weights is None else weights
    fun, jac = _problem(model, observations, spec, noise, fixed, w, evaluations)
    values, iterations = levenberg_marquardt(fun, jac, fixed[free], max_iterations)
    delta = fixed.copy()
    delta[free] = values
    return delta, iterations


def frozen_jacobian(
    model: CalibrationModel,
    observations: Observations,
    spec: Spec,
    noise: Noise,
    x: FloatArray,
    evaluations: Evaluations | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Whitened Jacobian of the free deviations at ``x``: per posture (n, 3 or 9, f), and the prior rows (q, f).

    ``evaluations``: as :func:`fit`'s (the fit that ended at ``x`` evaluated the model there).
    """
    free = list(spec.free)
    out = _evaluations_of(model, observations, evaluations).evaluate(x, jacobian=True, floor=spec.floor)
    blocks = [out.contact_jacobian / np.array(noise.contact)[None, :, None]]
    if spec.floor:
        blocks.append(out.floor_jacobian / np.array(noise.floor)[None, :, None])
    per_posture = projection(model.basis[:, free])(np.concatenate(blocks, axis=1))  # (n, m, f)
    sd = spec.prior_sd[free]
    prior = np.isfinite(sd)
    return per_posture, np.diag(1.0 / np.where(prior, sd, 1.0))[prior]


def held_at_urdf(model: CalibrationModel, spec: Spec, x: FloatArray) -> FloatArray:
    """``x`` with every direction the spec does not free, except planes and floor constants, at the URDF."""
    delta = model.delta_of(x)
    held = np.ones(model.size, dtype=bool)
    held[list(spec.free)] = False
    held[model.columns([Kind.PLANE, Kind.FLOOR])] = False
    delta[held] = 0.0
    return model.x_of(delta)


def _hat_terms(
    model: CalibrationModel,
    observations: Observations,
    spec: Spec,
    noise: Noise,
    delta: FloatArray,
    evaluations: Evaluations | None = None,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Whitened data Jacobian (m, f), residuals, leverage of each data row (m,), posterior covariance (f, f)."""
    free = np.array(spec.free, dtype=int)
    fun, jac = _problem(model, observations, spec, noise, delta, np.ones(len(observations)), evaluations)
    values = delta[free]
    full = jac(values)
    n_data = len(observations) * (9 if spec.floor else 3)
    data = full[:n_data]
    information = full.T @ full
    covariance = np.linalg.pinv(information)
    leverage = np.sum((data @ covariance) * data, axis=1)
    return data, fun(values)[:n_data], leverage, covariance


def estimate_noise(
    model: CalibrationModel,
    observations: Observations,
    spec: Spec,
    noise: Noise,
    delta: FloatArray,
    evaluations: Evaluations | None = None,
) -> Noise:
    """Noise per component: residual RMS corrected for the fitted degrees of freedom.

    ``evaluations``: as :func:`fit`'s (the fit that ended at ``delta`` evaluated its residuals there).
    """
    _, whitened, leverage, _ = _hat_terms(model, observations, spec, noise, delta, evaluations)
    n = len(observations)
    contact = whitened[: 3 * n].reshape(n, 3) * np.array(noise.contact)
    dof = leverage[: 3 * n].reshape(n, 3).sum(axis=0)
    rows = row_mask(observations.contacts.kinds).sum(axis=0)  # (3,) measured rows per component
    sigma_c = np.sqrt(np.sum(contact**2, axis=0) / np.maximum(rows - dof, 1.0))
    sigma_c = np.where(rows > 0, sigma_c, np.array(noise.contact))  # no flush contact: roll, pitch unmeasured
    sigma_f = np.array(noise.floor)
    if spec.floor:
        floor = whitened[3 * n :].reshape(n, 6) * sigma_f
        dof_f = leverage[3 * n :].reshape(n, 6).sum(axis=0)
        sigma_f = np.sqrt(np.sum(floor**2, axis=0) / np.maximum(n - dof_f, 1.0))
    return Noise.of(sigma_c, sigma_f)


def estimate(
    model: CalibrationModel,
    observations: Observations,
    spec: Spec,
    noise: Noise,
    start: FloatArray,
    rounds: int = 2,
    max_iterations: int = 50,
    warm: Sequence[FloatArray] = (),
    evaluations: Evaluations | None = None,
) -> Estimate:
    """MAP estimate with the noise re-estimated from its own residuals ``rounds`` times.

    ``warm``: for each fit, parameters (nx,) to start its free directions from (the same
    fit's result on nearly the same rows); the others start from the previous fit (the
    first from ``start``). Each fit converges to the same optimum from either start.
    ``evaluations``: the model's at ``observations``, shared with what follows the estimate
    (its Jacobian at the estimate); None: the estimate's own.
    """
    x = start
    delta = model.delta_of(start)
    iterations = 0
    points = []
    converged = True
    # each fit ends where its noise is estimated and the next one starts
    evaluations = evaluations if evaluations is not None else Evaluations(model, observations)
    for k in range(rounds + 1):
        begin = _warm_start(model, spec, x, warm[k]) if k < len(warm) else x
        delta, used = fit(model, observations, spec, noise, begin, max_iterations, evaluations=evaluations)
        iterations += used
        converged = converged and used < max_iterations
        x = model.x_of(delta)
        points.append(x)
        if k < rounds:
            noise = estimate_noise(model, observations, spec, noise, delta, evaluations)
    _, _, _, covariance = _hat_terms(model, observations, spec, noise, delta, evaluations)
    std = np.zeros(model.size)
    std[list(spec.free)] = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
    return Estimate(x, delta, noise, iterations, std, tuple(points) if converged else ())


def _warm_start(model: CalibrationModel, spec: Spec, x: FloatArray, warm: FloatArray) -> FloatArray:
    """``x`` with its free directions taken from ``warm``."""
    delta = model.delta_of(x)
    free = list(spec.free)
    delta[free] = model.delta_of(warm)[free]
    return model.x_of(delta)


def plane_spec(model: CalibrationModel, sessions: set[str] | None = None) -> Spec:
    """Only the planes (of ``sessions``, or all) free, no prior: kinematics frozen."""
    free = tuple(
        i for i, d in enumerate(model.directions) if d.kind == Kind.PLANE and (sessions is None or d.owner in sessions)
    )
    return Spec(free, np.full(model.size, np.inf), floor=False)
