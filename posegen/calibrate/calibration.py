"""Whole calibration from contacts: base parameters, before/after fits, prior by CV, outliers.

* Base parameters are structural: QR of the regressor at the nominal model over seeded
  random postures of every (chain, session) pair the training set has.
* "Before": nominal kinematics, only plane and contact parameters fitted.
* "After": every base parameter, MAP with a prior of size ``kappa`` x (1 mm, 0.1 deg);
  ``kappa`` and the measurement noise per component are chosen by K-fold
  cross-validation on the training contacts only.
* Outliers: training contacts whose cross-validated residual, scaled by the noise,
  exceeds a chi (3 dof) bound (Bonferroni: 1 % chance of any false alarm in a clean
  data set) are reported and left out of the final fit.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.stats
from numpy.typing import NDArray

from posegen.calibrate.identification import Fit, identify, refit_planes
from posegen.errors import InfeasibleError
from posegen.model import (
    DEFAULT_NOISE,
    NOISE_FLOOR,
    STRUCTURAL_POSTURES,
    BaseParameters,
    ContactModel,
    Contacts,
    Group,
    Weights,
    initial_planes,
    structural_base,
    weights_for,
)
from posegen.progress import ProgressCallback, Steps, ignore_progress
from posegen.robot import FloatArray, Indices, Scene

LOG = logging.getLogger(__name__)


@dataclass(frozen=True)
class Settings:
    """How a calibration is run."""

    kappas: tuple[float, ...] = (1.0, 2.0, 3.0, 5.0, 10.0)  # prior sizes tried, x (1 mm, 0.1 deg)
    kappa: float | None = None  # fixed prior size: skips cross-validation
    noise: tuple[float, float, float] = DEFAULT_NOISE  # initial sigma
    folds: int = 5
    outlier_false_alarm: float = 0.01  # chance of flagging any contact of a clean data set (Bonferroni)
    drop_outliers: bool = True
    structural_postures: int = STRUCTURAL_POSTURES  # per (chain, session) pair
    seed: int = 0


@dataclass(frozen=True)
class CvPoint:
    """Cross-validated score of one prior size."""

    kappa: float
    score: float  # mean normalised squared prediction error per contact
    mean_abs: tuple[float, float, float]  # m, rad, rad


@dataclass(frozen=True)
class Calibration:
    """Result of a calibration."""

    model: ContactModel
    base: BaseParameters
    train: Contacts
    before: Fit
    after: Fit
    weights: Weights
    cv: tuple[CvPoint, ...]
    outliers: tuple[int, ...]  # indices in ``train`` left out of the final fit
    outlier_scores: tuple[float, ...]  # their normalised CV residual
    kept: tuple[int, ...] = field(default=())  # indices in ``train`` used by the final fit


def outlier_threshold(n: int, false_alarm: float) -> float:
    """Normalised residual above which one of n contacts is an outlier.

    sqrt of the chi-square (3 dof) quantile at 1 - false_alarm / n: a clean data set of n
    contacts has a chance ``false_alarm`` of showing any.
    """
    return float(np.sqrt(scipy.stats.chi2.ppf(1.0 - false_alarm / max(n, 1), 3)))


def _folds(contacts: Contacts, k: int, seed: int) -> NDArray[np.int_]:
    """Fold index per contact, stratified by session. Shape (n,)."""
    rng = np.random.default_rng(seed)
    fold = np.zeros(len(contacts), dtype=int)
    sessions = np.array(contacts.sessions)
    for session in sorted(set(contacts.sessions)):
        rows = np.flatnonzero(sessions == session)
        fold[rng.permutation(rows)] = np.arange(len(rows)) % k
    return fold


def cross_validate(
    model: ContactModel,
    contacts: Contacts,
    free: Indices,
    weights: Weights,
    theta0: FloatArray,
    k: int,
    seed: int,
) -> FloatArray:
    """Residual of each contact predicted by a fit on the other folds. Shape (n, 3)."""
    fold = _folds(contacts, k, seed)
    out = np.zeros((len(contacts), 3))
    for f in range(k):
        test = np.flatnonzero(fold == f)
        if len(test) == 0:
            continue
        fit = identify(model, contacts.subset(np.flatnonzero(fold != f)), free, weights, theta0)
        out[test] = model.residuals(fit.theta, contacts.subset(test))
    return out


def calibrate(
    scene: Scene,
    train: Contacts,
    sessions: Sequence[str],
    settings: Settings | None = None,
    progress: ProgressCallback = ignore_progress,
    base: BaseParameters | None = None,
) -> Calibration:
    """Calibrate the chains seen in ``train``.

    Args:
        scene: Scene (robot model and config).
        train: Training contacts.
        sessions: Every session the model must know (training and held-out).
        settings: How to run; defaults if None.
        progress: Told when each step starts.
        base: Base parameters to use (of a model of the same chains and sessions);
            None: found by :func:`structural_base`.

    Raises:
        InfeasibleError: Too few contacts to cross-validate or to fit.

    """
    settings = settings or Settings()
    if len(train) < 2 * settings.folds:
        raise InfeasibleError(f"{len(train)} training contacts: at least {2 * settings.folds} are needed")
    kappas = (settings.kappa,) if settings.kappa is not None else settings.kappas
    rounds = 2 if len(kappas) > 1 else 1  # the second with the noise re-estimated by the first
    say = Steps(3 + rounds * len(kappas), progress)
    model = ContactModel(scene, sorted(set(train.chains)), sessions)
    say("base parameters")
    if base is None:
        base = structural_base(model, train, settings.noise, settings.structural_postures, settings.seed)
    start = initial_planes(model, train, model.nominal())
    side = np.array([i for i in base.columns if model.parameters[i].group in (Group.PLANE, Group.CONTACT)], dtype=int)
    say("before: plane and contact parameters")
    before = identify(model, train, side, weights_for(1e6, settings.noise), start)

    noise = np.array(settings.noise)
    cv_points: list[CvPoint] = []
    cv_res: FloatArray = np.zeros((len(train), 3))
    kappa = kappas[0]
    for _round in range(rounds):
        cv_points = []
        best = np.inf
        for candidate in kappas:
            say(f"cross-validation, prior x{candidate:g}")
            res = cross_validate(
                model, train, base.columns, weights_for(candidate, noise), before.theta, settings.folds, settings.seed
            )
            score = float(np.mean(np.sum((res / noise) ** 2, axis=1)))
            mean_abs = np.mean(np.abs(res), axis=0)
            cv_points.append(CvPoint(candidate, score, (float(mean_abs[0]), float(mean_abs[1]), float(mean_abs[2]))))
            if score < best:
                best, kappa, cv_res = score, candidate, res
        noise = np.maximum(np.sqrt(np.mean(cv_res**2, axis=0)), NOISE_FLOOR)  # re-estimated from CV
    weights = weights_for(kappa, noise)
    scores = np.sqrt(np.sum((cv_res / noise) ** 2, axis=1))
    threshold = outlier_threshold(len(train), settings.outlier_false_alarm)
    outliers = np.flatnonzero(scores > threshold) if settings.drop_outliers else np.array([], dtype=int)
    kept = np.setdiff1d(np.arange(len(train)), outliers)
    for i in outliers:
        LOG.warning("outlier contact %s: normalised CV residual %.1f", train.labels[i], scores[i])
    say("after: all base parameters")
    after = identify(model, train.subset(kept), base.columns, weights, before.theta)
    return Calibration(
        model=model,
        base=base,
        train=train,
        before=before,
        after=after,
        weights=weights,
        cv=tuple(cv_points),
        outliers=tuple(int(i) for i in outliers),
        outlier_scores=tuple(float(scores[i]) for i in outliers),
        kept=tuple(int(i) for i in kept),
    )


def held_out_theta(calibration: Calibration, fit: Fit, contacts: Contacts) -> FloatArray:
    """Protocol 1: the held-out sessions take the plane fitted with the same chain in training.

    A session also present in training keeps its own plane. Another session takes the
    plane of the training session with the most contacts of the held-out chain: the
    plane's height is only known relative to the chain it was fitted with.
    """
    model = calibration.model
    theta = fit.theta.copy()
    train = calibration.train
    for session in sorted(set(contacts.sessions) - set(train.sessions)):
        chains = [c for c, s in zip(contacts.chains, contacts.sessions, strict=True) if s == session]
        chain = max(set(chains), key=chains.count)
        counts = {
            s: sum(1 for c, t in zip(train.chains, train.sessions, strict=True) if c == chain and t == s)
            for s in set(train.sessions)
        }
        source = max(sorted(counts), key=lambda s: counts[s])
        if counts[source] == 0:
            raise InfeasibleError(f"chain '{chain}' of held-out session '{session}' has no training contact")
        theta[model.plane_columns(session)] = theta[model.plane_columns(source)]
    return theta


def held_out_residuals(calibration: Calibration, contacts: Contacts) -> dict[str, dict[str, FloatArray]]:
    """Held-out residuals (n, 3) per protocol ("training_plane", "refitted_plane") and model."""
    model = calibration.model
    out: dict[str, dict[str, FloatArray]] = {"training_plane": {}, "refitted_plane": {}}
    for name, fit in (("before", calibration.before), ("after", calibration.after)):
        theta = held_out_theta(calibration, fit, contacts)
        out["training_plane"][name] = model.residuals(theta, contacts)
        refit = refit_planes(model, contacts, theta, calibration.weights)
        out["refitted_plane"][name] = model.residuals(refit, contacts)
    return out
