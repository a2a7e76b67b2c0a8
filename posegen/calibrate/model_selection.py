"""Choosing the model by repeated, grouped cross-validation on the training rows only.

Every candidate model is fitted at prior scales of the config's grid; each fit is judged
on the rows that the folds of :mod:`posegen.calibrate.folds` hold out (regions of the
table, or sessions), with the held-out rows' sessions' planes from training (re-fitted
on a new session). A fold's fit starts from the fit on all rows at the same candidate and
scale and takes ``fold_iterations`` Gauss-Newton steps, at that fit's noise. Scores and
the rules that read them: :mod:`posegen.calibrate.scoring`.

**Scale search.** A candidate's score over the prior scale is a valley: too strong a
prior cannot move the parameters, too weak a one fits the noise (and then leaves the
plausible range). The search starts at the grid's middle scale and walks up while the
score falls, then down from the middle while a scale may still be within reach of the
rules (its score within two standard errors of the candidate's best). Every fit is
warm-started from its neighbour towards the middle, so the scales it computes are
computed exactly as the exhaustive search (:attr:`ScaleSearch.EXHAUSTIVE`, every scale)
computes them; a test compares the two picks on the real recordings.

**Plausibility.** Every measurement is zero, so a model whose contact height does not
depend on the posture at all fits, and "predicts", every height exactly: with a weak
prior a flexible model finds such solutions (a leg 380 mm longer, a sole and the table
tilted 27 deg), and cross-validation scores them well on the height. A pair whose fit
on all rows moves any length by more than ``plausible_mm`` or any angle by more than
``plausible_deg`` from the URDF is not a calibration of this robot, nor is one whose
joints give way against their load (a negative compliance): it is reported and left out
of the rules (and not cross-validated); weaker priors of that candidate are not tried.

**Workers.** Candidates are independent: they run over the backend's workers, each
candidate's scales in one process, and come back in the config's order, so the result
is the same bytes for any number of workers.
"""

from __future__ import annotations

import enum
import hashlib
import logging
import pickle
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import partial

import numpy as np

from posegen.calibrate.estimation import (
    Estimate,
    Noise,
    estimate,
    fit,
    frozen_jacobian,
    held_at_urdf,
    plane_spec,
)
from posegen.calibrate.folds import Fold
from posegen.calibrate.frozen_refits import refit_frozen_folds
from posegen.calibrate.scoring import CvResult, implausible, one_standard_error, score_folds
from posegen.errors import InfeasibleError
from posegen.model import (
    CalibrationModel,
    Evaluations,
    Kind,
    Observations,
    Spec,
    candidate_spec,
    masked,
    spec_for_rows,
    start_point,
)
from posegen.parallel import Backend, Job, as_backend
from posegen.progress import ProgressCallback, Steps, ignore_progress
from posegen.robot import CalibrationConfig, CandidateConfig, FloatArray

LOG = logging.getLogger(__name__)
NOMINAL = CandidateConfig("nominal URDF", ())  # only the contact offsets and planes: the URDF as it is
REACH_SE = 2.0  # a smaller scale is still tried while its score is within this many standard errors of the best


class ScaleSearch(str, enum.Enum):
    """Which prior scales of the grid a candidate is cross-validated at."""

    VALLEY = "valley"  # from the middle scale, while the score falls or may still be within reach
    EXHAUSTIVE = "exhaustive"  # every scale (benchmarks, and the test of the valley search)


@dataclass(frozen=True)
class ModelSelection:
    """Every result, the chosen pair, and how stable the choice is over the fold seeds."""

    results: tuple[CvResult, ...]
    best: CvResult
    chosen: CvResult
    seed_picks: tuple[tuple[str, float], ...]  # (candidate, scale) the rule picks on each seed alone
    estimates: dict[tuple[str, float], Estimate]  # the fit on all training rows of each pair
    nominal: CvResult  # the URDF as it is (contact offsets and planes fitted), scored alike

    @property
    def stability(self) -> float:
        """Share of the seeds whose own pick is the chosen pair."""
        key = (self.chosen.candidate, self.chosen.prior_scale)
        return sum(p == key for p in self.seed_picks) / max(len(self.seed_picks), 1)


@dataclass(frozen=True)
class Problem:
    """What every candidate's cross-validation shares (sent once to each worker)."""

    model: CalibrationModel
    observations: Observations
    config: CalibrationConfig
    folds: tuple[Fold, ...]
    noise: Noise
    search: ScaleSearch
    warm: Mapping[tuple[str, float], tuple[FloatArray, ...]]  # (candidate, scale) -> its fits' results, to start from


def cross_validate(
    model: CalibrationModel,
    observations: Observations,
    spec: Spec,
    full: Estimate,
    folds: Sequence[Fold],
    iterations: int,
    evaluations: Evaluations | None = None,
) -> list[FloatArray]:
    """Predicted contact residuals (t, 3) of each fold's held-out rows, NaN where a contact measures nothing.

    A region fold's fit takes ``iterations`` Gauss-Newton steps from the fit on all rows,
    with that fit's Jacobian frozen; a session fold (whose plane is unknown in training)
    takes Levenberg-Marquardt steps. ``evaluations``: the model's at ``observations``, as
    the fit on all rows left them (its Jacobian at ``full.x``).
    """
    if not folds:
        return []
    jacobian = frozen_jacobian(model, observations, spec, full.noise, full.x, evaluations)
    frozen = [k for k, fold in enumerate(folds) if _fold_spec(model, spec, observations, fold).free == spec.free]
    deltas = dict(
        zip(
            frozen,
            refit_frozen_folds(
                model, observations, spec, full.noise, full.x, jacobian, [folds[k].train for k in frozen], iterations
            ),
            strict=True,
        )
    )
    xs = []
    for k, fold in enumerate(folds):
        if k not in deltas:
            own = _fold_spec(model, spec, observations, fold)
            deltas[k], _ = fit(model, observations.subset(fold.train), own, full.noise, full.x, iterations)
        x = model.x_of(deltas[k])
        if fold.new_session:
            test = observations.subset(fold.test)
            planes = plane_spec(model, set(test.contacts.sessions))
            x = model.x_of(fit(model, test, planes, full.noise, start_point_planes(model, test, x))[0])
        xs.append(x)
    contact, _ = model.evaluate_batch(np.array(xs), observations, floor=False)  # (F, n, 3): every fold at every row
    kinds = observations.contacts.kinds
    return [masked(contact[k, list(fold.test)], [kinds[i] for i in fold.test]) for k, fold in enumerate(folds)]


def _fold_spec(model: CalibrationModel, spec: Spec, observations: Observations, fold: Fold) -> Spec:
    """``spec`` less the planes of sessions the fold's training rows lack (their planes are unknown there)."""
    return spec_for_rows(model, spec, {observations.contacts.sessions[i] for i in fold.train})


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


def score_pair(
    problem: Problem, candidate: CandidateConfig, scale: float, start: FloatArray
) -> tuple[CvResult, Estimate]:
    """Fit one (candidate, scale) pair on all rows from ``start`` (nx,) and cross-validate it (unless implausible)."""
    model, observations, config = problem.model, problem.observations, problem.config
    sessions = set(observations.contacts.sessions)
    spec = spec_for_rows(model, candidate_spec(model, candidate, config.prior, scale), sessions)
    warm = problem.warm.get((candidate.name, scale), ())
    evaluations = Evaluations(model, observations)  # the fit's last Jacobian is the folds' frozen one
    full = estimate(
        model, observations, spec, problem.noise, held_at_urdf(model, spec, start), warm=warm, evaluations=evaluations
    )
    largest = largest_deviations(model, full.delta)
    negative = sorted(g for g, c in model.compliances(full.x).items() if g in candidate.compliance and c < 0.0)
    if largest[0] > config.plausible_mm or largest[1] > config.plausible_deg or negative:
        LOG.info(
            "%s at prior x%g: %.0f mm, %.1f deg from the URDF, negative compliance %s: implausible",
            candidate.name,
            scale,
            *largest,
            negative,
        )
        return implausible(candidate.name, scale, len(spec.free), full.noise, largest, problem.folds), full
    predicted = cross_validate(model, observations, spec, full, problem.folds, config.fold_iterations, evaluations)
    return score_folds(candidate.name, scale, len(spec.free), problem.folds, predicted, full.noise, largest), full


def _walk(
    problem: Problem,
    candidate: CandidateConfig,
    scales: Sequence[float],
    start: FloatArray,
    upward: bool,
    seen: Sequence[CvResult] = (),
) -> list[tuple[CvResult, Estimate]]:
    """Score ``scales`` in order, each warm-started from the previous fit; stop as the search rule says.

    ``seen`` are the candidate's results at other scales (the best of them counts in the rule).
    """
    out: list[tuple[CvResult, Estimate]] = []
    x = start
    for scale in scales:
        # warm-started from the neighbouring scale's fit, but never from its noise: the noise and the
        # prior's weight are estimated together, and from a weaker prior's small noise a strong prior
        # would barely pull (a fixed point of its own, far from the one the default noise leads to)
        result, full = score_pair(problem, candidate, scale, x)
        out.append((result, full))
        if not result.plausible:
            if upward and problem.search == ScaleSearch.VALLEY:
                break  # weaker priors are more flexible still
            continue
        x = full.x
        plausible = [r for r in seen if r.plausible] + [r for r, _ in out[:-1] if r.plausible]
        if problem.search == ScaleSearch.EXHAUSTIVE or not plausible:
            continue
        best = min(plausible, key=lambda r: r.score)
        if upward and result.score > best.score:
            break
        if not upward and result.score > best.score + REACH_SE * max(best.se, result.se):
            break
    return out


def score_candidate(problem: Problem, candidate: CandidateConfig) -> list[tuple[CvResult, Estimate]]:
    """Every scale the search tries for one candidate, in ascending scale order."""
    scales = sorted(problem.config.prior_scales)
    middle = len(scales) // 2
    start = start_point(problem.model, problem.observations)
    if candidate.name == NOMINAL.name:  # the URDF as it is: the scale only weighs the contact offsets' prior
        return _walk(problem, candidate, scales[middle : middle + 1], start, upward=True)
    up = _walk(problem, candidate, scales[middle:], start, upward=True)
    first = up[0]
    down_start = first[1].x if first[0].plausible else start
    down = _walk(problem, candidate, scales[:middle][::-1], down_start, upward=False, seen=[r for r, _ in up])
    return sorted(up + down, key=lambda pair: pair[0].prior_scale)


def _model_state(payload: bytes) -> CalibrationModel:
    model = pickle.loads(payload)
    assert isinstance(model, CalibrationModel)
    return model


def _score_item(model: CalibrationModel, item: tuple[bytes, CandidateConfig]) -> list[tuple[CvResult, Estimate]]:
    """:func:`score_candidate` in a worker: the model is its state (built once), the rest comes with the item."""
    inputs, candidate = item
    return score_candidate(Problem(model, *pickle.loads(inputs)), candidate)


def select_model(
    model: CalibrationModel,
    observations: Observations,
    settings: CalibrationConfig,
    folds: Sequence[Fold],
    noise: Noise,
    candidates: Sequence[CandidateConfig] | None = None,
    progress: ProgressCallback = ignore_progress,
    backend: Backend | None = None,
    search: ScaleSearch = ScaleSearch.VALLEY,
    warm: Mapping[tuple[str, float], tuple[FloatArray, ...]] | None = None,
) -> ModelSelection:
    """Cross-validate every candidate over the prior scales and apply the one-standard-error rule.

    Args:
        model: Calibration model.
        observations: Training rows (flagged rows already left out).
        settings: The config's calibration section (prior, scales, fold iterations).
        folds: The folds (of these rows).
        noise: Starting noise of each fit.
        candidates: Candidates to try; None: the config's. Floor candidates are skipped
            when the chains do not reach both soles.
        progress: Told when each candidate is done.
        backend: Where the candidates run; None: this process.
        search: Which prior scales are tried.
        warm: (candidate, scale) -> the results of its fits on nearly the same rows
            (:attr:`Estimate.rounds` of an earlier selection): each fit of that pair on
            all rows starts from them, and converges to the same optimum in fewer steps.

    Raises:
        InfeasibleError: Every candidate's fit is implausible.

    """
    usable = [c for c in (candidates or settings.candidates) if not (c.floor and model.floor is None)]
    for skipped in set(candidates or settings.candidates) - set(usable):
        LOG.info("candidate %s skipped: the floor equations need a chain from each sole", skipped.name)
    rest = (observations, settings, tuple(folds), noise, search, dict(warm or {}))  # a Problem's, but the model
    # the workers' state is the model alone: a second selection (other rows) runs on the same workers
    payload = pickle.dumps(model)
    job: Job[CalibrationModel, tuple[bytes, CandidateConfig], list[tuple[CvResult, Estimate]]] = Job(
        name=f"calibrate-cv-{hashlib.sha256(payload).hexdigest()[:16]}",
        setup=partial(_model_state, payload),
        run=_score_item,
    )
    inputs = pickle.dumps(rest)
    say = Steps(len(usable) + 1, progress)
    items = [*usable, NOMINAL]
    # the costliest first (floor equations, then the most free parameters): no worker waits long for the last
    cost = {c.name: (c.floor, len(candidate_spec(model, c, settings.prior, 1.0).free)) for c in items}
    order = sorted(range(len(items)), key=lambda i: cost[items[i].name], reverse=True)
    by_item: dict[int, list[tuple[CvResult, Estimate]]] = {}
    runner = as_backend(backend or 1)
    for i, scored in zip(order, runner.map(job, [(inputs, items[i]) for i in order], len(items)), strict=True):
        say(f"cross-validation: {items[i].name}")
        by_item[i] = scored
    *scored_candidates, nominal = [by_item[i] for i in range(len(items))]  # the config's order, whatever ran first
    results = [r for pairs in scored_candidates for r, _ in pairs]
    estimates = {(r.candidate, r.prior_scale): e for pairs in scored_candidates for r, e in pairs}
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
    nominal_best = min(nominal, key=lambda pair: (pair[0].score, pair[0].prior_scale))
    estimates[NOMINAL.name, nominal_best[0].prior_scale] = nominal_best[1]
    return ModelSelection(
        results=tuple(results),
        best=results[min((i for i, r in enumerate(results) if r.plausible), key=lambda i: scores[i])],
        chosen=results[chosen],
        seed_picks=tuple(picks),
        estimates=estimates,
        nominal=nominal_best[0],
    )
