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
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.stats
from numpy.typing import NDArray

from posegen.contact_model import ContactModel, Contacts, Group
from posegen.errors import InfeasibleError
from posegen.geometry import FloatArray, Indices
from posegen.identifiability import BaseParameters, base_parameters
from posegen.identification import Fit, Weights, identify, initial_planes, prior_scale, refit_planes
from posegen.scene import Scene
from posegen.simulation import settle

LOG = logging.getLogger(__name__)

UNIT_PRIOR_LENGTH_M = 1e-3
UNIT_PRIOR_ANGLE_RAD = float(np.deg2rad(0.1))
NOISE_FLOOR = (1e-5, float(np.deg2rad(1e-3)), float(np.deg2rad(1e-3)))  # no contact is known better


@dataclass(frozen=True)
class Settings:
    """How a calibration is run."""

    kappas: tuple[float, ...] = (1.0, 2.0, 3.0, 5.0, 10.0)  # prior sizes tried, x (1 mm, 0.1 deg)
    kappa: float | None = None  # fixed prior size: skips cross-validation
    noise: tuple[float, float, float] = (1e-3, UNIT_PRIOR_ANGLE_RAD, UNIT_PRIOR_ANGLE_RAD)  # initial sigma
    folds: int = 5
    outlier_false_alarm: float = 0.01  # chance of flagging any contact of a clean data set (Bonferroni)
    drop_outliers: bool = True
    structural_postures: int = 100  # per (chain, session) pair
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


def weights_for(kappa: float, noise: Sequence[float] | FloatArray) -> Weights:
    """Weights with a prior of size kappa x (1 mm, 0.1 deg)."""
    return Weights(
        noise=(float(noise[0]), float(noise[1]), float(noise[2])),
        prior_length_m=kappa * UNIT_PRIOR_LENGTH_M,
        prior_angle_rad=kappa * UNIT_PRIOR_ANGLE_RAD,
    )


def structural_base(model: ContactModel, contacts: Contacts, settings: Settings) -> BaseParameters:
    """Base parameters of the (chain, session) pairs present in ``contacts``."""
    rich = level_postures(model, contacts, settings.structural_postures, settings.seed)
    theta = initial_planes(model, rich, model.nominal())
    _, jac = model.jacobian(theta, rich)
    noise = np.array(settings.noise)
    regressor = (jac / noise[None, :, None]).reshape(-1, model.size)
    scale = prior_scale(model, weights_for(1.0, settings.noise))
    scale[~np.isfinite(scale)] = UNIT_PRIOR_LENGTH_M
    planes = model.columns(Group.PLANE)
    robot = np.concatenate([model.columns(Group.PLACEMENT), model.columns(Group.CONTACT)])
    return base_parameters(regressor, scale, [planes, robot])


def level_postures(model: ContactModel, contacts: Contacts, n: int, seed: int) -> Contacts:
    """Random standing contacts of each (chain, session) pair of ``contacts``.

    Shaped like real ones, because the regressor's rank depends on it: both soles on
    the floor (the stance closure ties the two legs), and every contact flush with a
    level plane at its session's mean contact height (one height per session removes
    combinations that varying heights would show). Each is a training contact with
    every joint perturbed at random (legs by up to 0.3 rad, the rest by up to 0.5 rad),
    the second leg closed onto its sole and the contact settled by the smallest arm and
    torso motion.
    """
    scene = model.scene
    rng = np.random.default_rng(seed)
    legs = scene.stance_leg_joints()
    spread = np.full(len(scene.joint_names), 0.5)
    spread[legs] = 0.3
    theta = initial_planes(model, contacts, model.nominal())
    for session in model.sessions:  # level planes at the measured heights
        theta[model.index[f"plane@{session}.roll"]] = theta[model.index[f"plane@{session}.pitch"]] = 0.0
    pairs = sorted(set(zip(contacts.chains, contacts.sessions, strict=True)))
    parts: list[Contacts] = []
    for chain, session in pairs:
        seeds = contacts.joints[
            [
                i
                for i, (c, s) in enumerate(zip(contacts.chains, contacts.sessions, strict=True))
                if (c, s) == (chain, session)
            ]
        ]
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
            batch = Contacts(
                np.array(samples), (chain,) * len(samples), (session,) * len(samples), ("",) * len(samples)
            )
            settled, converged = settle(model, theta, batch)
            keep = np.flatnonzero(converged)[: n - found]
            parts.append(settled.subset(keep))
            found += len(keep)
            if found >= n:
                break
        else:
            raise InfeasibleError(f"cannot generate standing contacts like those of chain '{chain}'")
    out = parts[0]
    for part in parts[1:]:
        out = out.concat(part)
    return out


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
    progress: Callable[[str], None] | None = None,
    base: BaseParameters | None = None,
) -> Calibration:
    """Calibrate the chains seen in ``train``.

    Args:
        scene: Scene (robot model and config).
        train: Training contacts.
        sessions: Every session the model must know (training and held-out).
        settings: How to run; defaults if None.
        progress: Called with a short description of each step.
        base: Base parameters to use (of a model of the same chains and sessions);
            None: found by :func:`structural_base`.

    Raises:
        InfeasibleError: Too few contacts to cross-validate or to fit.

    """
    settings = settings or Settings()
    say = progress or (lambda _: None)
    if len(train) < 2 * settings.folds:
        raise InfeasibleError(f"{len(train)} training contacts: at least {2 * settings.folds} are needed")
    model = ContactModel(scene, sorted(set(train.chains)), sessions)
    say("base parameters")
    if base is None:
        base = structural_base(model, train, settings)
    start = initial_planes(model, train, model.nominal())
    side = np.array([i for i in base.columns if model.parameters[i].group in (Group.PLANE, Group.CONTACT)], dtype=int)
    say("before: plane and contact parameters")
    before = identify(model, train, side, weights_for(1e6, settings.noise), start)

    noise = np.array(settings.noise)
    kappas = (settings.kappa,) if settings.kappa is not None else settings.kappas
    cv_points: list[CvPoint] = []
    cv_res: FloatArray = np.zeros((len(train), 3))
    kappa = kappas[0]
    for _round in range(2 if len(kappas) > 1 else 1):
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
        for fld in ("z", "roll", "pitch"):
            theta[model.index[f"plane@{session}.{fld}"]] = theta[model.index[f"plane@{source}.{fld}"]]
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
