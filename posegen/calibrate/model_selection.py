"""Choosing the model by repeated, grouped cross-validation on the training rows only.

Every candidate model is fitted at every prior scale; each fit is judged on the rows
that the folds of :mod:`posegen.calibrate.folds` hold out (regions of the table, or
sessions), with the held-out rows' sessions' planes from training (re-fitted on a new
session). A fold's fit starts from the fit on all rows at the same candidate and scale
and takes ``fold_iterations`` Levenberg-Marquardt steps, at that fit's noise.

Score: the mean over held-out contacts of sum_c (e_c / u_c)^2, with u = (1 mm, 0.1 deg,
0.1 deg) the units the experiment design weighs in, averaged over the chains (each
chain counts alike, however many rows it has). It counts measured rows: three times the
mean of (e_c / u_c)^2 over the rows measured, which is the above for flush contacts and
weighs a point contact (its height only) as one row, not three. Its standard error is that of one
repetition: the spread of the fold scores over the square root of their number, per
chain, combined over the chains and averaged over the seeds.

**Rule.** Among the (candidate, scale) pairs whose score is within one standard error
of the best, take the candidate with the fewest free parameters, then its strongest
prior (smallest scale) within that bound. Stability: the same rule applied to each
seed's folds alone; the share of seeds that pick the same pair.

**Plausibility.** Every measurement is zero, so a model whose contact height does not
depend on the posture at all fits, and "predicts", every height exactly: with a weak
prior a flexible model finds such solutions (a leg 380 mm longer, a sole and the table
tilted 27 deg), and cross-validation scores them well on the height. A pair whose fit
on all rows moves any length by more than ``plausible_mm`` or any angle by more than
``plausible_deg`` from the URDF is not a calibration of this robot: it is reported and
left out of the rule (and not cross-validated).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from posegen.calibrate.estimation import (
    Estimate,
    Noise,
    estimate,
    fit,
    frozen_jacobian,
    held_at_urdf,
    plane_spec,
    refit_frozen,
)
from posegen.calibrate.folds import Fold
from posegen.errors import InfeasibleError
from posegen.model import (
    DEFAULT_NOISE,
    CalibrationModel,
    Kind,
    Observations,
    Spec,
    candidate_spec,
    masked,
    spec_for_rows,
    start_point,
)
from posegen.progress import ProgressCallback, Steps, ignore_progress
from posegen.robot import CalibrationConfig, CandidateConfig, FloatArray

LOG = logging.getLogger(__name__)
RULE = (
    "among the (candidate, prior scale) pairs scoring within one standard error of the best, the candidate with "
    "the fewest free parameters, then its strongest prior (smallest scale) within that bound"
)
SCORE_UNITS = np.array(DEFAULT_NOISE)  # (1 mm, 0.1 deg, 0.1 deg): how the score weighs the components


@dataclass(frozen=True)
class ChainError:
    """Cross-validated prediction error of one chain's contacts."""

    mean_abs: tuple[float, float, float]  # m, rad, rad
    rms: tuple[float, float, float]  # m, rad, rad
    score: float


@dataclass(frozen=True)
class CvResult:
    """One candidate at one prior scale, as cross-validation judged it."""

    candidate: str
    prior_scale: float
    free: int  # number of free parameters
    score: float
    se: float
    seed_scores: tuple[float, ...]
    seed_se: tuple[float, ...]
    chains: dict[str, ChainError]
    noise: Noise  # estimated on all training rows
    largest: tuple[float, float]  # largest deviation of the fit on all rows from the URDF: mm, deg
    plausible: bool = True  # within the config's plausible deviations (else not cross-validated)


@dataclass(frozen=True)
class ModelSelection:
    """Every result, the chosen pair, and how stable the choice is over the fold seeds."""

    results: tuple[CvResult, ...]
    best: CvResult
    chosen: CvResult
    seed_picks: tuple[tuple[str, float], ...]  # (candidate, scale) the rule picks on each seed alone
    estimates: dict[tuple[str, float], Estimate]  # the fit on all training rows of each pair

    @property
    def stability(self) -> float:
        """Share of the seeds whose own pick is the chosen pair."""
        key = (self.chosen.candidate, self.chosen.prior_scale)
        return sum(p == key for p in self.seed_picks) / max(len(self.seed_picks), 1)


def cross_validate(
    model: CalibrationModel,
    observations: Observations,
    spec: Spec,
    full: Estimate,
    folds: Sequence[Fold],
    iterations: int,
) -> list[FloatArray]:
    """Predicted contact residuals (t, 3) of each fold's held-out rows, NaN where a contact measures nothing.

    A region fold's fit takes ``iterations`` Gauss-Newton steps from the fit on all rows,
    with that fit's Jacobian frozen; a session fold (whose plane is unknown in training)
    takes Levenberg-Marquardt steps.
    """
    per_posture, prior_rows = frozen_jacobian(model, observations, spec, full.noise, full.x)
    out = []
    for fold in folds:
        train = observations.subset(fold.train)
        test = observations.subset(fold.test)
        own = spec_for_rows(model, spec, set(train.contacts.sessions))
        if own.free == spec.free:
            rows = (per_posture[list(fold.train)], prior_rows)
            delta = refit_frozen(model, train, spec, full.noise, full.x, rows, iterations)
        else:
            delta, _ = fit(model, train, own, full.noise, full.x, iterations)
        x = model.x_of(delta)
        if fold.new_session:
            sessions = set(test.contacts.sessions)
            planes = plane_spec(model, sessions)
            x = model.x_of(fit(model, test, planes, full.noise, start_point_planes(model, test, x))[0])
        out.append(masked(model.evaluate(x, test, floor=False).contact, test.contacts.kinds))
    return out


def start_point_planes(model: CalibrationModel, observations: Observations, x: FloatArray) -> FloatArray:
    """``x`` with the planes of the observations' sessions level at their mean height."""
    start = start_point(model, observations)
    out = x.copy()
    for session in set(observations.contacts.sessions):
        out[model.contact.plane_columns(session)] = start[model.contact.plane_columns(session)]
    return out


LENGTH_KINDS = (Kind.LINK_TRANSLATION, Kind.CONTACT_HEIGHT, Kind.CONTACT_POINT)
ANGLE_KINDS = (Kind.JOINT_OFFSET, Kind.AXIS_TILT, Kind.FRAME_ROTATION, Kind.CONTACT_TILT)


def largest_deviations(model: CalibrationModel, delta: FloatArray) -> tuple[float, float]:
    """Largest deviation from the URDF of any length (mm) and any angle (deg)."""
    lengths = np.abs(delta[model.columns(LENGTH_KINDS)])
    angles = np.abs(delta[model.columns(ANGLE_KINDS)])
    return float(lengths.max(initial=0.0) * 1e3), float(np.degrees(angles.max(initial=0.0)))


def fold_loss(predicted: FloatArray) -> tuple[float, int]:
    """Sum of (e_c / u_c)^2 over the measured rows of (t, 3) residuals (NaN: not measured), and their number."""
    measured = np.isfinite(predicted)
    return float(np.sum(np.where(measured, predicted / SCORE_UNITS, 0.0) ** 2)), int(measured.sum())


def column_stats(errors: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Mean absolute and RMS of each column of (t, 3) residuals over its measured rows (NaN: none). Shapes (3,)."""
    measured = np.isfinite(errors)
    count = measured.sum(axis=0)
    values = np.where(measured, errors, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_abs = np.where(count > 0, np.abs(values).sum(axis=0) / count, np.nan)
        rms = np.where(count > 0, np.sqrt((values**2).sum(axis=0) / count), np.nan)
    return mean_abs, rms


def score_folds(
    candidate: str,
    scale: float,
    free: int,
    folds: Sequence[Fold],
    predicted: Sequence[FloatArray],
    noise: Noise,
    largest: tuple[float, float],
) -> CvResult:
    """Score, standard error, per-seed and per-chain figures of one pair's fold predictions."""
    seeds = sorted({f.seed for f in folds})
    chains = sorted({f.chain for f in folds})
    seed_scores, seed_se = [], []
    errors: dict[str, list[FloatArray]] = {c: [] for c in chains}
    for seed in seeds:
        chain_scores, chain_var = [], []
        for chain in chains:
            mine = [p for f, p in zip(folds, predicted, strict=True) if f.seed == seed and f.chain == chain]
            losses = [fold_loss(p) for p in mine]  # (sum, measured rows) per fold
            chain_scores.append(3.0 * sum(v for v, _ in losses) / max(sum(m for _, m in losses), 1))
            fold_means = np.array([3.0 * v / max(m, 1) for v, m in losses])
            chain_var.append(float(np.var(fold_means, ddof=1) / len(fold_means)) if len(fold_means) > 1 else 0.0)
            errors[chain].append(np.vstack(mine))
        seed_scores.append(float(np.mean(chain_scores)))
        seed_se.append(float(np.sqrt(np.sum(chain_var)) / len(chains)))
    per_chain = {}
    for chain in chains:
        stats = [column_stats(e) for e in errors[chain]]
        mean_abs = np.mean([m for m, _ in stats], axis=0)
        rms = np.mean([r for _, r in stats], axis=0)
        score = np.mean([3.0 * v / max(m, 1) for v, m in (fold_loss(e) for e in errors[chain])])
        per_chain[chain] = ChainError(
            (float(mean_abs[0]), float(mean_abs[1]), float(mean_abs[2])),
            (float(rms[0]), float(rms[1]), float(rms[2])),
            float(score),
        )
    return CvResult(
        candidate=candidate,
        prior_scale=scale,
        free=free,
        score=float(np.mean(seed_scores)),
        se=float(np.sqrt(np.mean(np.square(seed_se)))),
        seed_scores=tuple(seed_scores),
        seed_se=tuple(seed_se),
        chains=per_chain,
        noise=noise,
        largest=largest,
    )


def implausible(
    candidate: str, scale: float, free: int, noise: Noise, largest: tuple[float, float], folds: Sequence[Fold]
) -> CvResult:
    """A pair left out of the rule: no score (inf)."""
    seeds = len({f.seed for f in folds})
    nan3 = (float("nan"),) * 3
    chains = {f.chain: ChainError(nan3, nan3, float("inf")) for f in folds}
    inf = float("inf")
    return CvResult(candidate, scale, free, inf, inf, (inf,) * seeds, (inf,) * seeds, chains, noise, largest, False)


def one_standard_error(results: Sequence[CvResult], scores: FloatArray, errors: FloatArray) -> int:
    """Index of the pair the rule picks among the plausible ones, given each pair's score and standard error."""
    plausible = [i for i, r in enumerate(results) if r.plausible]
    best = min(plausible, key=lambda i: scores[i])
    bound = scores[best] + errors[best]
    eligible = [i for i in plausible if scores[i] <= bound]
    fewest = min(results[i].free for i in eligible)
    simplest = [i for i in eligible if results[i].free == fewest]
    return min(simplest, key=lambda i: (results[i].prior_scale, results[i].candidate))


def select_model(
    model: CalibrationModel,
    observations: Observations,
    settings: CalibrationConfig,
    folds: Sequence[Fold],
    noise: Noise,
    candidates: Sequence[CandidateConfig] | None = None,
    progress: ProgressCallback = ignore_progress,
) -> ModelSelection:
    """Cross-validate every candidate at every prior scale and apply the one-standard-error rule.

    Args:
        model: Calibration model.
        observations: Training rows (flagged rows already left out).
        settings: The config's calibration section (prior, scales, fold iterations).
        folds: The folds (of these rows).
        noise: Starting noise of each fit.
        candidates: Candidates to try; None: the config's. Floor candidates are skipped
            when the chains do not reach both soles.
        progress: Told when each candidate's fits start.

    """
    usable = [c for c in (candidates or settings.candidates) if not (c.floor and model.floor is None)]
    for skipped in set(candidates or settings.candidates) - set(usable):
        LOG.info("candidate %s skipped: the floor equations need a chain from each sole", skipped.name)
    say = Steps(len(usable) * len(settings.prior_scales), progress)
    results: list[CvResult] = []
    estimates: dict[tuple[str, float], Estimate] = {}
    start = start_point(model, observations)
    sessions = set(observations.contacts.sessions)
    for candidate in usable:
        x = start
        for scale in settings.prior_scales:
            say(f"cross-validation: {candidate.name}, prior x{scale:g}")
            spec = spec_for_rows(model, candidate_spec(model, candidate, settings.prior, scale), sessions)
            full = estimate(model, observations, spec, noise, held_at_urdf(model, spec, x))
            largest = largest_deviations(model, full.delta)
            estimates[candidate.name, scale] = full
            if largest[0] > settings.plausible_mm or largest[1] > settings.plausible_deg:
                LOG.info(
                    "%s at prior x%g: %.0f mm, %.1f deg from the URDF: implausible", candidate.name, scale, *largest
                )
                results.append(implausible(candidate.name, scale, len(spec.free), full.noise, largest, folds))
                continue
            x = full.x  # warm start of the next scale
            predicted = cross_validate(model, observations, spec, full, folds, settings.fold_iterations)
            results.append(score_folds(candidate.name, scale, len(spec.free), folds, predicted, full.noise, largest))
    if not any(r.plausible for r in results):
        raise InfeasibleError("every candidate's fit is implausible (see calibration.plausible_mm, plausible_deg)")
    scores = np.array([r.score for r in results])
    errors = np.array([r.se for r in results])
    chosen = one_standard_error(results, scores, errors)
    picks = []
    for s in range(len(results[0].seed_scores)):
        seed_scores = np.array([r.seed_scores[s] for r in results])
        seed_errors = np.array([r.seed_se[s] for r in results])
        pick = results[one_standard_error(results, seed_scores, seed_errors)]
        picks.append((pick.candidate, pick.prior_scale))
    return ModelSelection(
        results=tuple(results),
        best=results[min((i for i, r in enumerate(results) if r.plausible), key=lambda i: scores[i])],
        chosen=results[chosen],
        seed_picks=tuple(picks),
        estimates=estimates,
    )
