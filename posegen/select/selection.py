"""Posture selection: IROC, DETMAX baseline and exact k-posture designs.

IROC (as in the 2025 TALOS paper): continuous D-optimal weights, postures ranked by
weight, the top k stacked from k0 (the fewest with nb measured rows: ceil(nb / 3) flush
contacts, nb point contacts) with O1(k) = det(I(q_k))^(1/(2 nb)) /
sqrt(k); the selection is where O1 stops rising. ``select_k`` finds an exact design of
a given size: the best of greedy, the IROC top-k and the best DETMAX run, each polished
by Fedorov exchange, so it never scores below either baseline.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from posegen.model import SINGULAR, Design
from posegen.robot import FloatArray
from posegen.select.optimal_weights import OptimalWeights, d_optimal_weights
from posegen.select.subset_selection import Subset, detmax, exchange, greedy, subset_of

SUPPORT_WEIGHT = 1e-6  # weights below this are outside the support


@dataclass(frozen=True)
class Iroc:
    """The IROC selection and what it was read from."""

    weights: OptimalWeights
    ranking: tuple[int, ...]  # pool rows by decreasing weight
    curve: tuple[tuple[int, float], ...]  # (k, O1 of the top k)
    selected: Subset  # the top k where O1 stops rising
    o1_star: float  # O1 of the optimal continuous design: no k-subset exceeds it
    fractions: dict[float, int | None]  # smallest k whose O1 reaches each fraction of O1*
    support: int  # postures with a weight above SUPPORT_WEIGHT
    weight_drop_k: int  # rank after which the sorted weights fall the most (relative)


def iroc(design: Design, fractions: Sequence[float] = (0.9, 0.95), tolerance: float = 1e-4) -> Iroc:
    """Run IROC on a design.

    Args:
        design: Candidate postures.
        fractions: Report the smallest k reaching these fractions of O1*.
        tolerance: Kiefer-Wolfowitz gap at which the weights are optimal enough.

    """
    weights = d_optimal_weights(design, tolerance)
    ranking = tuple(int(i) for i in np.argsort(-weights.weights, kind="stable"))
    k0 = design.fewest(ranking)
    support = int(np.sum(weights.weights > SUPPORT_WEIGHT))
    curve = _o1_curve(design, ranking, k0)
    positive = [(k, v) for k, v in curve if v > 0]
    selected_k = next(
        (positive[i][0] for i in range(len(positive) - 1) if positive[i + 1][1] <= positive[i][1]),
        max(curve, key=lambda p: p[1])[0],
    )
    o1_star = design.o1_of_weights(weights.weights)
    reached: dict[float, int | None] = {}
    for fraction in fractions:
        reached[fraction] = next((k for k, value in curve if value >= fraction * o1_star), None)
    sorted_w = weights.weights[list(ranking[:support])]
    drops = sorted_w[:-1] / np.maximum(sorted_w[1:], 1e-300)
    return Iroc(
        weights=weights,
        ranking=ranking,
        curve=tuple(curve),
        selected=subset_of(design, ranking[:selected_k]),
        o1_star=o1_star,
        fractions=reached,
        support=support,
        weight_drop_k=int(np.argmax(drops)) + 1 if len(drops) else support,
    )


def _o1_curve(design: Design, ranking: Sequence[int], k0: int) -> list[tuple[int, float]]:
    """O1 of the top k for k = k0, k0 + 1, ...: an R factor updated 3 rows at a time.

    Stops once k is 30 % past the best k so far (and past 3 k0), or at the pool size.
    """
    nb = design.n_params
    r = np.linalg.qr(design.stacked(ranking[:k0]), mode="r")
    curve: list[tuple[int, float]] = []
    best_k, best = k0, 0.0
    for k in range(k0, design.size + 1):
        if k > k0:
            r = np.linalg.qr(np.vstack([r, design.regressors[ranking[k - 1]]]), mode="r")
        diag = np.abs(np.diag(r))[:nb]
        full = len(diag) == nb and np.all(diag > SINGULAR * diag.max())
        value = float(np.exp((2 * np.sum(np.log(diag)) + design.log_det_pool) / (2 * nb)) / np.sqrt(k)) if full else 0.0
        curve.append((k, value))
        if value > best:
            best_k, best = k, value
        if k > max(3 * k0, int(1.3 * best_k)):
            break
    return curve


def detmax_runs(design: Design, k: int, runs: int, seed: int) -> tuple[Subset, ...]:
    """Independent DETMAX runs from seeded random starts (run r uses seed (seed, r))."""
    return tuple(detmax(design, k, np.random.default_rng([seed, r])) for r in range(runs))


def select_k(
    design: Design,
    k: int,
    ranking: Sequence[int],
    baseline: Sequence[Subset] = (),
) -> Subset:
    """Best exact design of k postures found from several starts.

    Args:
        design: Candidate postures.
        k: Number of postures.
        ranking: IROC ranking (its top k is one start).
        baseline: DETMAX results to polish and beat.

    """
    starts: list[Subset] = []
    starts.append(greedy(design, k))
    starts.append(subset_of(design, list(ranking[:k])))
    starts.extend(baseline)
    best: Subset | None = None
    for start in sorted(starts, key=lambda s: -s.score)[:3]:
        polished = exchange(design, start)
        if best is None or polished.score > best.score:
            best = polished
    assert best is not None
    return best


def weight_of(iroc_result: Iroc, rows: Sequence[int]) -> FloatArray:
    """IROC weights of some postures. Shape (k,)."""
    return np.asarray(iroc_result.weights.weights[list(rows)], dtype=float)
