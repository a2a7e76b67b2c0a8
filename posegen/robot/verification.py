"""The verdict of an independent re-check: the worst case of each invariant.

Shared by ``posegen check`` of pools (:mod:`posegen.pool`) and of routes
(:mod:`posegen.route`).
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Generic, TypeVar

import numpy as np

from posegen.robot.geometry import FloatArray

if TYPE_CHECKING:
    from posegen.robot.coverage import GeometryCoverage

K = TypeVar("K", bound=enum.Enum)

EXAMPLES = 5  # violations named per invariant by :func:`worst_case`


@dataclass(frozen=True)
class Worst:
    """The worst case of one invariant over a set of postures."""

    invariant: enum.Enum  # an Invariant, or a route's invariant
    excess: float  # how far past its bound (> 0: violated), in the invariant's unit
    posture: int  # index of the posture (or route point) where it occurs
    violations: int  # number of postures (or points) violating it
    detail: str
    examples: tuple[str, ...] = ()  # the first violations, each named (where, what, value, limit)
    checked: bool = True  # False: not checked, because an earlier defect makes it meaningless


@dataclass(frozen=True)
class JointEffort:
    """The worst holding torque of one joint over the checked postures or points."""

    joint: str
    ratio: float  # abs(torque) / URDF effort limit
    torque_nm: float
    limit_nm: float
    point: int  # where (posture or route point index)


@dataclass(frozen=True)
class Verification:
    """Result of re-checking postures."""

    checked: int
    worst: tuple[Worst, ...]  # one per invariant
    geometry: GeometryCoverage | None = None  # what the collisions were checked with
    efforts: tuple[JointEffort, ...] = ()  # each joint with an effort limit: its worst holding torque (routes)

    @property
    def ok(self) -> bool:
        """True if no posture violates any invariant."""
        return all(w.violations == 0 for w in self.worst)


def summarize(
    checked: int, excess: Mapping[K, Sequence[float] | FloatArray], details: Mapping[K, Sequence[str]]
) -> Verification:
    """The worst case of each invariant, in the mapping's order.

    Args:
        checked: Number of items checked.
        excess: Per invariant, each item's excess over its bound (> 0: violated).
        details: Per invariant, each item's description of what was measured.

    """
    worst = []
    for key, values in excess.items():
        array = np.asarray(values, dtype=float)
        if array.size == 0:
            worst.append(Worst(key, 0.0, -1, 0, "nothing checked"))
            continue
        i = int(np.argmax(array))
        worst.append(Worst(key, float(array[i]), i, int(np.sum(array > 0)), details[key][i]))
    return Verification(checked=checked, worst=tuple(worst))


class WorstSoFar(Generic[K]):
    """The worst case of each invariant over items told one at a time.

    Keeps one detail per invariant, not one per item, so a check can stream any number
    of items; :meth:`result` equals :func:`summarize` of the same items.
    """

    def __init__(self, keys: Sequence[K]) -> None:
        self._keys = tuple(keys)
        self._excess = dict.fromkeys(self._keys, 0.0)
        self._index = dict.fromkeys(self._keys, -1)
        self._violations = dict.fromkeys(self._keys, 0)
        self._detail = dict.fromkeys(self._keys, "nothing checked")
        self.checked = 0

    def add(self, excess: Mapping[K, float], details: Mapping[K, str]) -> None:
        """Take the next item's excess per invariant (> 0: violated) and what was measured."""
        for key in self._keys:
            value = float(excess[key])
            best = self._excess[key]
            # np.argmax semantics: the first maximum, and a NaN beats any number
            if self._index[key] < 0 or value > best or (np.isnan(value) and not np.isnan(best)):
                self._excess[key], self._index[key], self._detail[key] = value, self.checked, details[key]
            self._violations[key] += value > 0
        self.checked += 1

    def result(self) -> Verification:
        """The verdict over every item told so far."""
        return Verification(
            checked=self.checked,
            worst=tuple(
                Worst(k, self._excess[k], self._index[k], self._violations[k], self._detail[k]) for k in self._keys
            ),
        )


def worst_case(invariant: enum.Enum, excess: FloatArray, describe: Callable[[int], str], ok: str) -> Worst:
    """The worst item of an invariant and its first violations, each described.

    Args:
        invariant: The invariant.
        excess: (n,) each item's excess over its bound (> 0 or NaN: violated; -inf: not checked).
        describe: Names a violation at an item (where, what, value, limit).
        ok: What to say when nothing is violated.

    """
    excess = np.where(np.isnan(excess), np.inf, np.asarray(excess, dtype=float))
    if not np.any(np.isfinite(excess) | (excess == np.inf)):
        return Worst(invariant, 0.0, -1, 0, "nothing to check")
    bad = np.flatnonzero(excess > 0)
    i = int(np.argmax(excess))
    detail = describe(i) if len(bad) else ok
    return Worst(invariant, float(excess[i]), i, len(bad), detail, tuple(describe(int(k)) for k in bad[:EXAMPLES]))
