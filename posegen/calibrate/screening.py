"""Screening the training rows: feet off the floor, and contacts the model cannot explain.

* **Feet.** Every posture stands on both soles. Under the URDF the second sole seems to
  move with the legs' joints (the legs' own errors); a robust fit of that first-order motion
  takes it out (:func:`feet_unexplained`), and a row whose remaining offset from the
  session's is beyond both the config's tolerance and six robust standard deviations of the
  rows' did not stand: it is left out before anything is fitted.
* **Bad rows.** A robust fit (a Cauchy loss on each posture's normalised residual,
  by iteratively reweighted least squares) cannot be pulled far by one bad row, so that
  row keeps a large residual. Each row's residual is studentised (divided by the noise,
  estimated consistently under the weights, and by the residual's standard deviation in
  the weighted, regularised fit: :func:`residual_variance`) and flagged above the chi bound
  (3 dof for a flush contact, 1 for a point contact, 6 more with the floor equations)
  at which a clean set of n rows shows any with probability ``false_alarm``
  (Bonferroni). Flagged rows are left out and the rest screened again (:class:`Screening`):
  monotone (a row left out stays out), bounded (at most ``calibration.max_left_out`` of
  the rows, then it stops and warns) and never fails.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.special

from posegen.calibrate.estimation import Noise, fit, frozen_jacobian
from posegen.model import CalibrationModel, Evaluations, Observations, Spec, Unit, row_counts, row_mask
from posegen.robot import CalibrationConfig, FloatArray

CAUCHY_SCALE = 2.385  # Cauchy constant of 95 % efficiency, per degree of freedom of a row
ROBUST_ITERATIONS = 8
MAX_ROUNDS = 6  # robust fits of one screening run, each without the rows the last one flagged


@dataclass(frozen=True)
class Flag:
    """A training row left out, and why."""

    row: int  # index in the rows read
    label: str  # file:line:spot
    reason: str  # "feet" or "residual"
    value: float  # normalised residual (chi) or the sole's offset (mm / deg, the larger)
    round: int  # screening round that flagged it (0: feet, before any fit)


def chi_threshold(n: int, false_alarm: float, dof: int = 3) -> float:
    """Normalised residual above which one of n rows is flagged (Bonferroni over n rows)."""
    return float(np.sqrt(2 * scipy.special.gammaincinv(dof / 2, 1.0 - false_alarm / max(n, 1))))  # chi2 quantile


def row_dof(observations: Observations, floor: bool) -> FloatArray:
    """Degrees of freedom of each row's residual: its contact's measured rows, 6 more with the floor. Shape (n,)."""
    return np.asarray(row_counts(observations.contacts.kinds) + (6 if floor else 0), dtype=float)


def chi_thresholds(dof: FloatArray, false_alarm: float) -> FloatArray:
    """:func:`chi_threshold` of each row, given its degrees of freedom (n,). Shape (n,)."""
    return np.array([chi_threshold(len(dof), false_alarm, int(d)) for d in dof])


def feet_offsets(model: CalibrationModel, observations: Observations) -> FloatArray:
    """Second sole's pose under the URDF less its session's median: (n, 6) m, m, m, rad, rad, rad."""
    assert model.floor is not None
    contacts = observations.contacts
    pose = model.floor.measure(model.contact.nominal(), contacts.joints)  # (n, 6)
    sessions = np.array(contacts.sessions)
    offset = pose.copy()
    for session in set(contacts.sessions):
        rows = sessions == session
        offset[rows] -= np.median(pose[rows], axis=0)
    return offset


def feet_unexplained(
    model: CalibrationModel, observations: Observations, tolerance: FloatArray, prior_sd: tuple[float, float]
) -> FloatArray:
    """The second sole's offsets (:func:`feet_offsets`) less what the legs' geometric errors explain. (n, 6).

    Under the URDF the second sole of a robot standing still seems to move from posture
    to posture: the legs' placement errors show through the leg joints, about D(q) d, D
    the sole pose's derivative w.r.t. the legs' placements at the URDF. A robust fit
    (Cauchy weights on each row's offset in tolerances, 8 reweightings) of d, with the
    prior's sigmas, and of each session's constant pose, takes that part out; a sole off
    the floor is no smooth function of the joints and stays.

    Args:
        model: The calibration model (with its floor equations).
        observations: The rows.
        tolerance: (6,) the config's tolerance per component (m, m, m, rad, rad, rad).
        prior_sd: Prior sigma of a leg placement's lengths (m) and of its angles (rad).

    """
    assert model.floor is not None
    contacts = model.contact
    theta = contacts.nominal()
    joints = observations.contacts.joints
    _, d_theta, _ = model.floor.derivatives(theta, joints)  # (n, 6, p)
    legs = np.flatnonzero(np.any(d_theta != 0.0, axis=(0, 1)))
    sigma = np.array([prior_sd[0] if contacts.parameters[i].unit == Unit.LENGTH else prior_sd[1] for i in legs])
    sessions = np.unique(np.array(observations.contacts.sessions), return_inverse=True)[1]  # (n,)
    n, k = len(joints), int(sessions.max()) + 1
    intercepts = np.zeros((n, 6, 6 * k))
    for component in range(6):
        intercepts[np.arange(n), component, 6 * sessions + component] = 1.0
    design = np.concatenate([d_theta[:, :, legs] * sigma, intercepts], axis=2) / tolerance[None, :, None]
    target = model.floor.measure(theta, joints) / tolerance  # (n, 6) in tolerances
    penalty = np.diag(np.r_[np.ones(len(legs)), np.zeros(6 * k)])  # d / sigma ~ N(0, 1); constants free
    weights = np.ones(n)
    residual = target
    for _ in range(ROBUST_ITERATIONS):
        flat = (design * np.sqrt(weights)[:, None, None]).reshape(6 * n, -1)
        rhs = (target * np.sqrt(weights)[:, None]).ravel()
        solution = np.linalg.lstsq(flat.T @ flat + penalty, flat.T @ rhs, rcond=None)[0]
        residual = target - design @ solution  # (n, 6)
        weights = 1.0 / (1.0 + np.sum(residual**2, axis=1))
    return residual * tolerance


def feet_off_the_floor(offsets: FloatArray, tolerance_m: float, tolerance_rad: float) -> FloatArray:
    """How far beyond its bound each row's sole offset is (> 1: off the floor). Shape (n,).

    A component's bound is the larger of the tolerance and six robust standard deviations
    (1.4826 x the median absolute offset) of that component over the rows: far beyond the
    noise, and beyond what a standing robot does.
    """
    spread = 1.4826 * np.median(np.abs(offsets), axis=0)  # (6,)
    tolerance = np.array([tolerance_m] * 3 + [tolerance_rad] * 3)
    bound = np.maximum(tolerance, 6.0 * spread)
    return np.max(np.abs(offsets) / bound, axis=1)


def residual_variance(jacobian: tuple[FloatArray, FloatArray], weights: FloatArray) -> FloatArray:
    """Each residual's variance over the noise's, in a weighted, regularised least-squares fit. Shape (n, m).

    The fit moves the residuals r = (I - M) e of noise e, with M = J A J^T W and A = (J^T W J
    + P^T P)^-1 (J whitened rows, W the rows' weights, P the prior's rows): their variance is
    [(I - M)(I - M)^T]_ii = 1 - 2 M_ii + [J A (J^T W^2 J) A J^T]_ii. Without weights or prior
    M is a projection and this is the familiar 1 - h_ii; a prior (a fit of more parameters
    than rows, regularised) makes it smaller, and 1 - h_ii would overstate it.

    Args:
        jacobian: The whitened Jacobian per posture (n, m, f) and the prior rows (q, f)
            (:func:`posegen.calibrate.estimation.frozen_jacobian`).
        weights: (n,) each posture's weight in the fit.

    Example:
        >>> residual_variance(frozen_jacobian(model, observations, spec, noise, x), np.ones(len(observations)))

    """
    per_posture, prior_rows = jacobian
    n, m, f = per_posture.shape
    row_weights = np.repeat(weights, m)  # (n m,)
    flat = per_posture.reshape(-1, f) * np.sqrt(row_weights)[:, None]  # W^1/2 J
    inverse = np.linalg.pinv(flat.T @ flat + prior_rows.T @ prior_rows)  # A
    spread = flat @ inverse  # W^1/2 J A
    leverage = np.sum(spread * flat, axis=1)  # M_ii
    second = np.sum((spread @ (flat.T @ (row_weights[:, None] * flat))) * spread, axis=1) / row_weights
    return np.clip(1.0 - 2.0 * leverage + second, 0.05, 1.0).reshape(n, m)


@functools.lru_cache(maxsize=32)
def cauchy_consistency(dof: int) -> float:
    """E[w S^2] / (dof E[w]) for a clean row: S^2 ~ chi2(dof), w = 1 / (1 + S^2 / (dof c^2)) its Cauchy weight.

    What a Cauchy-weighted mean square makes of the noise variance (0.79 for one degree of
    freedom, 0.91 for three): the screening's noise estimate is divided by it, so that the
    studentised residuals of clean rows are chi-distributed and the bound flags them at its
    stated rate.

    Example:
        >>> round(cauchy_consistency(1), 3), round(cauchy_consistency(3), 3)
        (0.795, 0.914)

    """
    # S^2 = 2 t, t ~ Gamma(dof / 2): generalised Gauss-Laguerre nodes of weight t^(dof/2 - 1) e^-t (the
    # Gamma function cancels in the ratio); the weight is smooth on [0, inf): 200 nodes reach 1e-12
    nodes, node_weights = scipy.special.roots_genlaguerre(200, dof / 2 - 1)
    squares = 2.0 * nodes
    cauchy = node_weights / (1.0 + squares / (dof * CAUCHY_SCALE**2))
    return float(np.sum(cauchy * squares) / (dof * np.sum(cauchy)))


def robust_residuals(
    model: CalibrationModel, observations: Observations, spec: Spec, noise: Noise, start: FloatArray
) -> tuple[FloatArray, FloatArray, Noise]:
    """Studentised residual of each row under a Cauchy-weighted fit (n,), the fit's parameters, its noise.

    A row's residual has 3 degrees of freedom (a flush contact; 1 for a point contact), 6
    more with the floor equations (:func:`row_dof`).
    """
    n = len(observations)
    weights = np.ones(n)
    x = start
    comps = 9 if spec.floor else 3
    dof = row_dof(observations, spec.floor)  # (n,)
    measured = np.hstack([row_mask(observations.contacts.kinds), np.ones((n, comps - 3), dtype=bool)])  # (n, comps)
    studentised = np.zeros(n)
    robust: FloatArray | None = None  # the first fit is unweighted: its mean square needs no correction
    evaluations = Evaluations(model, observations)  # each fit ends where the residuals are read, the next starts
    for _ in range(ROBUST_ITERATIONS):
        delta, _ = fit(model, observations, spec, noise, x, weights=weights, evaluations=evaluations)
        x = model.x_of(delta)
        out = evaluations.evaluate(x, floor=spec.floor)
        raw = np.hstack([out.contact, out.floor]) if spec.floor else out.contact  # (n, comps)
        sigma = np.array(noise.contact + noise.floor)[:comps]
        jacobian = frozen_jacobian(model, observations, spec, noise, x, evaluations)
        variance = residual_variance(jacobian, weights)  # (n, comps)
        scaled = (raw / sigma) ** 2 / variance  # (n, comps)
        studentised = np.sqrt(scaled.sum(axis=1))
        # noise of the well-fitting rows: weighted, leverage-corrected mean square over the measured rows, and
        # consistent: divided by what the weights make of a clean row's mean square (they shrink its largest draws)
        shrink = np.ones(n) if robust is None else robust  # (n,)
        weight_rows = (weights[:, None] * shrink[:, None] * measured).sum(axis=0)  # (comps,)
        mean_square = (weights[:, None] * raw**2 / variance).sum(axis=0)
        rms = np.where(weight_rows > 0, np.sqrt(mean_square / np.maximum(weight_rows, 1e-300)), sigma)
        noise = Noise.of(rms[:3], rms[3:] if spec.floor else np.array(noise.floor))
        weights = 1.0 / (1.0 + studentised**2 / (dof * CAUCHY_SCALE**2))
        robust = np.array([cauchy_consistency(int(d)) for d in dof])
    return studentised, x, noise


class Screening:
    """Monotone screening of the usable rows: a row left out stays out, and at most a share of them.

    Each :meth:`run` fits the kept rows robustly with a given model, leaves out the rows
    beyond their bound, and repeats without them (a gross error can hide a smaller one:
    masking) until nothing more is flagged, at most ``max_rounds`` times. Rows are never
    taken back, so the rows kept can only shrink: the screening ends. It stops leaving
    rows out at ``config.max_left_out`` of the usable rows and says so in
    :attr:`warnings`; it never fails.

    Example:
        >>> screen = Screening(model, observations, labels, usable, config, drop=True)
        >>> screen.run(spec, noise, start)  # True: new rows were flagged
        >>> screen.kept, screen.flags, screen.warnings

    """

    def __init__(
        self,
        model: CalibrationModel,
        observations: Observations,
        labels: Sequence[str],
        usable: Sequence[int],
        config: CalibrationConfig,
        drop: bool,
        max_rounds: int = MAX_ROUNDS,
    ) -> None:
        self._model = model
        self._observations = observations
        self._labels = tuple(labels)
        self._usable = tuple(usable)
        self._false_alarm = config.outlier_false_alarm
        self._drop = drop
        self._max_rounds = max_rounds
        self._share = config.max_left_out
        self.limit = int(np.floor(config.max_left_out * len(usable)))  # rows that may be left out
        self.flags: list[Flag] = []
        self.warnings: list[str] = []
        self._round = 0

    @property
    def kept(self) -> list[int]:
        """Rows the fits use: the usable ones less those left out (all of them with ``drop`` off)."""
        out = {f.row for f in self.flags} if self._drop else set()
        return [i for i in self._usable if i not in out]

    @property
    def dropped(self) -> list[Flag]:
        """The flags of the rows left out."""
        return list(self.flags) if self._drop else []

    def run(self, spec: Spec, noise: Noise, start: FloatArray) -> bool:
        """Screen the kept rows with a model until nothing more is flagged; whether any new row was.

        Args:
            spec: The model (free directions, prior, floor equations) of the robust fit.
            noise: Starting noise of the robust fit.
            start: (nx,) starting parameters.

        """
        flagged_any = False
        for _ in range(self._max_rounds):
            self._round += 1
            rows = [i for i in self._usable if i not in {f.row for f in self.flags}]
            subset = self._observations.subset(rows)
            studentised, _, noise = robust_residuals(self._model, subset, spec, noise, start)
            bounds = chi_thresholds(row_dof(subset, spec.floor), self._false_alarm)
            beyond = sorted(
                ((float(v), row) for row, v, b in zip(rows, studentised, bounds, strict=True) if v > b), reverse=True
            )
            if not beyond:
                return flagged_any
            room = self.limit - len(self.flags)
            for value, row in beyond[: max(room, 0)]:
                self.flags.append(Flag(row, self._labels[row], "residual", value, self._round))
                flagged_any = True
            if len(beyond) > room:
                self.warnings.append(
                    f"screening stopped at its limit of {self.limit} rows left out ({self._share:.0%} of "
                    f"{len(self._usable)}, calibration.max_left_out): "
                    f"{len(beyond) - max(room, 0)} more row(s) beyond their bound kept, largest residual "
                    f"{beyond[max(room, 0)][0]:.1f}; the data may hold a systematic error the model lacks"
                )
                return flagged_any
            if not self._drop:
                return flagged_any  # flagged rows stay in: the next round would see the same
        self.warnings.append(f"screening still flagged rows after {self._max_rounds} rounds; the rest are kept")
        return flagged_any
