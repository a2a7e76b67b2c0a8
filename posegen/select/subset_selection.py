"""Exact designs of k postures: greedy, Fedorov exchange, DETMAX.

All three maximise log det(I + ridge) of the stacked information of k postures: the
exact log det when the set identifies every base parameter, and otherwise a score that
puts more identified directions first (a time budget may be too small for all). The search keeps
M^-1 and C = A M^-1 (every candidate's regressor times M^-1) and updates them by rank-3
Woodbury steps when a posture enters or leaves; a small ridge keeps M invertible while
the set is still too small. Every accepted exchange is confirmed by an exact QR
score (:meth:`Design.score`), which keeps the search honest near saturation.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from posegen.errors import InfeasibleError
from posegen.model import RIDGE, Design
from posegen.robot import FloatArray

IMPROVEMENT = 1e-9  # smallest log-det gain that counts


class _State:
    """A set of postures with M^-1 and C = A M^-1 kept up to date."""

    def __init__(self, design: Design, rows: Sequence[int]) -> None:
        self.a = design.regressors
        self.rows = list(rows)
        self.refresh()

    def copy(self) -> _State:
        """An independent copy (cheaper than a refresh)."""
        other = object.__new__(_State)
        other.a = self.a
        other.rows = list(self.rows)
        other.inverse = self.inverse.copy()
        other.c = self.c.copy()
        return other

    def refresh(self) -> None:
        nb = self.a.shape[2]
        info = RIDGE * np.eye(nb)
        if self.rows:
            stacked = self.a[self.rows].reshape(-1, nb)
            info = info + stacked.T @ stacked
        self.inverse = np.linalg.inv(info)
        n = self.a.shape[0]
        self.c = (self.a.reshape(-1, nb) @ self.inverse).reshape(n, 3, nb)  # (n, 3, nb)

    def gains(self, sign: float) -> FloatArray:
        """Log det change of adding (sign +1) or removing (-1) each candidate. Shape (n,)."""
        b = self.c @ self.a.transpose(0, 2, 1)  # A_j M^-1 A_j^T, (n, 3, 3)
        sign_det, value = np.linalg.slogdet(np.eye(3)[None] + sign * b)
        return np.where(sign_det > 0, value, -np.inf)

    def update(self, j: int, sign: float) -> None:
        """Add (sign +1) or remove (-1) posture j: rank-3 Woodbury update."""
        g = self.c[j].T  # (nb, 3) = M^-1 A_j^T
        s = np.linalg.inv(sign * np.eye(3) + self.a[j] @ g)
        n, _, nb = self.a.shape
        ag = (self.a.reshape(-1, nb) @ g).reshape(n, 3, 3)
        self.c = self.c - (ag.reshape(-1, 3) @ (s @ g.T)).reshape(n, 3, nb)
        self.inverse = self.inverse - g @ s @ g.T
        if sign > 0:
            self.rows.append(j)
        else:
            self.rows.remove(j)


@dataclass(frozen=True)
class Subset:
    """An exact design."""

    rows: tuple[int, ...]  # posture indices, in the order they were chosen
    score: float  # log det(I + ridge): what the searches maximise (rank first)
    rank: int  # base parameters identified
    o1: float  # 0 unless every base parameter is identified


def subset_of(design: Design, rows: Sequence[int]) -> Subset:
    """The exact design of some postures, scored."""
    return Subset(
        rows=tuple(int(r) for r in rows), score=design.score(rows), rank=design.rank(rows), o1=design.o1(rows)
    )


def _check_k(design: Design, k: int) -> None:
    minimum = design.fewest()
    if not minimum <= k <= design.size:
        raise InfeasibleError(
            f"k = {k}: choose between {minimum} (the fewest postures with nb = {design.n_params} measured rows; "
            f"identifying all {design.n_params} base parameters may take more; IROC, k unset, finds how many) "
            f"and {design.size} (the pool)"
        )


def greedy(design: Design, k: int, start: Sequence[int] = ()) -> Subset:
    """Add, one at a time, the posture that raises log det most (rank-3 updates)."""
    _check_k(design, k)
    state = _State(design, start)
    while len(state.rows) < k:
        gains = state.gains(+1.0)
        gains[state.rows] = -np.inf
        state.update(int(np.argmax(gains)), +1.0)
    return subset_of(design, state.rows)


def exchange(design: Design, subset: Subset, max_swaps: int = 500) -> Subset:
    """Fedorov exchange: apply the best swap (one in, one out) until none improves."""
    rows = list(subset.rows)
    best = design.score(rows)
    nb = design.n_params
    for _ in range(max_swaps):
        state = _State(design, rows)
        b = state.c @ state.a.transpose(0, 2, 1)  # (n, 3, 3) A_j M^-1 A_j^T
        inside = np.array(rows)
        cross = (state.c.reshape(-1, nb) @ state.a[inside].reshape(-1, nb).T).reshape(design.size, 3, len(rows), 3)
        cross = cross.transpose(0, 2, 1, 3)  # (n, k, 3, 3) = A_j M^-1 A_i^T
        k = len(rows)
        blocks = np.zeros((design.size, k, 6, 6))
        blocks[:, :, :3, :3] = np.eye(3) + b[:, None]
        blocks[:, :, :3, 3:] = cross
        blocks[:, :, 3:, :3] = -cross.transpose(0, 1, 3, 2)
        blocks[:, :, 3:, 3:] = np.eye(3) - b[inside][None]
        sign, gain = np.linalg.slogdet(blocks)
        gain = np.where(sign > 0, gain, -np.inf)
        gain[inside] = -np.inf
        j, i = np.unravel_index(int(np.argmax(gain)), gain.shape)
        if gain[j, i] <= IMPROVEMENT:
            break
        trial = rows.copy()
        trial[i] = int(j)
        exact = design.score(trial)
        if not exact > best + IMPROVEMENT:
            break  # the update's promise did not survive the exact check
        rows, best = trial, exact
    return subset_of(design, rows)


def detmax(design: Design, k: int, rng: np.random.Generator, max_depth: int = 3) -> Subset:
    """DETMAX (Mitchell 1974) from a random k-subset, with excursions up to ``max_depth``.

    An excursion adds ``depth`` postures (each the best addition) then removes
    ``depth`` (each the cheapest removal), or the reverse; it is kept when log det rises.
    The search stops when no excursion up to the maximum depth improves the design.
    """
    _check_k(design, k)
    rows = [int(r) for r in rng.choice(design.size, size=k, replace=False)]
    state = _State(design, rows)
    best = design.score(rows)
    improved = True
    while improved:
        improved = False
        for depth in range(1, max_depth + 1):
            for add_first in (True, False):
                trial = _excursion(design, state.copy(), depth, add_first)
                value = design.score(trial.rows)
                if value > best + IMPROVEMENT:
                    state, best, improved = trial, value, True
                    break
            if improved:
                state.refresh()  # against drift of the rank-3 updates
                break
    return subset_of(design, state.rows)


def _excursion(design: Design, state: _State, depth: int, add_first: bool) -> _State:
    for phase in (+1.0, -1.0) if add_first else (-1.0, +1.0):
        for _ in range(depth):
            gains = state.gains(phase)
            if phase > 0:
                gains[state.rows] = -np.inf
            else:
                mask = np.full(design.size, -np.inf)
                mask[state.rows] = gains[state.rows]
                gains = mask
            state.update(int(np.argmax(gains)), phase)
    return state
