"""What a route does with a posture it cannot reach: another place in the order, then another posture.

A selection is an optimal *set*: a posture dropped from the route is information the
user paid for. So a posture whose transfer fails is first tried elsewhere in the order
(reached from other neighbours: the cheapest insertion places by rest-to-rest time),
and only when that fails too is it **substituted**: the pool posture that restores the
most information, i.e. the largest log det(I + A_j M^-1 A_j^T) gain given the postures
already routed (M their information, from the same design as the selection: the pool's
whitened base regressors), is routed in its place, and the swap is reported with O1
before and after.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from posegen.io import Posture
from posegen.model import Design

INSERTION_PLACES = 3  # places in the order tried for a posture that could not be reached where it was
SUBSTITUTE_TRIES = 8  # pool postures tried, by decreasing gain, in place of one lost posture


@dataclass(frozen=True)
class Substitutes:
    """The pool a selection came from, to repair it when a selected posture cannot be reached."""

    postures: tuple[Posture, ...]  # the pool's postures
    rows: tuple[int | None, ...]  # the pool row of each selected posture (None: not found in the pool)
    build_design: Callable[[], Design]  # the selection's design of the pool (built on first need)
    held: frozenset[int] = frozenset()  # pool rows never routed as a substitute (held in a session's earlier batch)

    def row(self, node: int, selected: int) -> int | None:
        """The pool row of a route node: nodes below ``selected`` are the selection's, the others substitutes."""
        return node - selected if node >= selected else self.rows[node]

    @functools.cached_property
    def design(self) -> Design:
        """The design, built once."""
        return self.build_design()


@dataclass(frozen=True)
class Substitution:
    """A selected posture that could not be routed, and the pool posture routed instead."""

    lost: int  # the lost posture's index in the selection
    reason: str  # why it could not be routed
    substitute: int  # the pool row routed instead
    gain: float  # its log det gain given the postures routed before it
    o1_before: float  # O1 of the selection as selected
    o1_after: float  # O1 of the postures routed once the substitute is in
    rank_before: int  # base parameters identified by the selection
    rank_after: int  # ... by the routed postures


def ranked_substitutes(substitutes: Substitutes, routed_rows: Sequence[int], tried: set[int]) -> list[int]:
    """Pool rows to try, by decreasing log det gain given the routed rows (selected, held and tried ones excluded)."""
    gains = substitutes.design.gains(list(routed_rows))
    excluded = {r for r in substitutes.rows if r is not None} | substitutes.held | tried
    gains[list(excluded)] = -np.inf
    order = np.argsort(-gains, kind="stable")
    return [int(r) for r in order[:SUBSTITUTE_TRIES] if np.isfinite(gains[r])]


def substitution(
    substitutes: Substitutes, lost: int, reason: str, row: int, routed_rows: Sequence[int]
) -> Substitution:
    """The record of a swap; ``routed_rows`` includes the substitute ``row``."""
    design = substitutes.design
    selected = [r for r in substitutes.rows if r is not None]
    before_others = [r for r in routed_rows if r != row]
    return Substitution(
        lost=lost,
        reason=reason,
        substitute=row,
        gain=float(design.gains(before_others)[row]),
        o1_before=design.o1(selected),
        o1_after=design.o1(list(routed_rows)),
        rank_before=design.rank(selected),
        rank_after=design.rank(list(routed_rows)),
    )


def insertion_places(sequence: Sequence[int], closed: bool, node: int, times: Callable[[int, int], float]) -> list[int]:
    """Where to insert ``node`` in the visiting order, cheapest first (at most INSERTION_PLACES).

    Args:
        sequence: The nodes visited, in order (the start posture is before the first).
        closed: Whether the route returns to the start posture after the last.
        node: The node to insert.
        times: Rest-to-rest time between two nodes (the start posture is node -1).

    Returns:
        Indices k: insert before ``sequence[k]`` (k == len(sequence): at the end).

    """
    start = -1
    costs: list[tuple[float, int]] = []
    for k in range(len(sequence) + 1):
        before = sequence[k - 1] if k > 0 else start
        after = sequence[k] if k < len(sequence) else (start if closed else None)
        cost = times(before, node)
        if after is not None:
            cost += times(node, after) - times(before, after)
        costs.append((cost, k))
    return [k for _, k in sorted(costs)[:INSERTION_PLACES]]


def o1_figures(substitutes: Substitutes, routed_rows: Sequence[int]) -> dict[str, float | int]:
    """O1 and rank of the selection as selected and of the postures routed (for the summary)."""
    design = substitutes.design
    selected = [r for r in substitutes.rows if r is not None]
    return {
        "o1_selected": design.o1(selected),
        "o1_routed": design.o1(list(routed_rows)),
        "rank_selected": design.rank(selected),
        "rank_routed": design.rank(list(routed_rows)),
        "base_parameters": design.n_params,
    }
