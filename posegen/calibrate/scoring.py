"""How cross-validation scores a (candidate, prior scale) pair, and the rules that pick one.

Score: the mean over held-out contacts of sum_c (e_c / u_c)^2, with u = (1 mm, 0.1 deg,
0.1 deg) the units the experiment design weighs in, averaged over the chains (each
chain counts alike, however many rows it has). It counts measured rows: three times the
mean of (e_c / u_c)^2 over the rows measured, which is the above for flush contacts and
weighs a point contact (its height only) as one row, not three. Its standard error is
that of one repetition: the spread of the fold scores over the square root of their
number, per chain, combined over the chains and averaged over the seeds.

Two rules read the scores:

* **the model** (what the calibration reports as this robot's physics, and what a
  follow-up design plans for): among the pairs within one standard error of the best,
  the candidate with the fewest free parameters, then its strongest prior within that
  bound (:func:`one_standard_error`);
* **a deliverable** (a file judged only by what it predicts: the URDF alone, or the URDF
  with its compliance compensation): the pair of lowest score among those the file can
  represent (:func:`lowest_score`). Parsimony buys an interpretable model; a file loaded
  by a controller is worth only its prediction error, which the score estimates.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from posegen.calibrate.estimation import Noise
from posegen.calibrate.folds import Fold
from posegen.model import DEFAULT_NOISE
from posegen.robot import FloatArray

RULE = (
    "among the (candidate, prior scale) pairs scoring within one standard error of the best, the candidate with "
    "the fewest free parameters, then its strongest prior (smallest scale) within that bound"
)
DELIVERABLE_RULE = "the plausible pair of lowest cross-validation score among those the file can represent"
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
    """A pair left out of the rules: no score (inf)."""
    seeds = len({f.seed for f in folds})
    nan3 = (float("nan"),) * 3
    chains = {f.chain: ChainError(nan3, nan3, float("inf")) for f in folds}
    inf = float("inf")
    return CvResult(candidate, scale, free, inf, inf, (inf,) * seeds, (inf,) * seeds, chains, noise, largest, False)


def one_standard_error(results: Sequence[CvResult], scores: FloatArray, errors: FloatArray) -> int:
    """Index of the pair the model rule picks among the plausible ones, given each pair's score and standard error.

    Example:
        >>> i = one_standard_error(results, np.array([r.score for r in results]), np.array([r.se for r in results]))

    """
    plausible = [i for i, r in enumerate(results) if r.plausible]
    best = min(plausible, key=lambda i: scores[i])
    bound = scores[best] + errors[best]
    eligible = [i for i in plausible if scores[i] <= bound]
    fewest = min(results[i].free for i in eligible)
    simplest = [i for i in eligible if results[i].free == fewest]
    return min(simplest, key=lambda i: (results[i].prior_scale, results[i].candidate))


def lowest_score(results: Sequence[CvResult], represents: Callable[[CvResult], bool]) -> CvResult | None:
    """The plausible pair of lowest score among those ``represents`` accepts (ties: fewer parameters, stronger prior).

    Example:
        >>> rigid = lowest_score(selection.results, lambda r: r.candidate in rigid_names)

    """
    eligible = [r for r in results if r.plausible and np.isfinite(r.score) and represents(r)]
    if not eligible:
        return None
    return min(eligible, key=lambda r: (r.score, r.free, r.prior_scale, r.candidate))
