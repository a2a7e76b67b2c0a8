"""Grouped cross-validation folds: whole regions of the table, or whole sessions.

A calibration must predict contacts it never saw, elsewhere on the table and on
another day. So the folds never split a group of rows that belong together:

* a spot (a session's target label; a row without one is its own spot) stays in one
  fold; its position is the nominal contact point in the chain's sole frame;
* a chain with one session is split into ``k`` contiguous regions of its spots: a
  balanced k-means (k-means++ start drawn from the seed, at most ceil(n / k) rows per
  region), each region one fold;
* a chain with several sessions is split by session: each fold holds one out (its
  plane is then re-fitted with the kinematics frozen, as for a new table session).

A fold holds out rows of one chain only; every other row trains. Repeating with other
seeds moves the region boundaries.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from posegen.model import ContactModel, Contacts
from posegen.robot import FloatArray


@dataclass(frozen=True)
class Fold:
    """One split of the training rows."""

    seed: int
    chain: str
    train: tuple[int, ...]
    test: tuple[int, ...]
    new_session: bool  # the test rows are a whole session: its plane is re-fitted


def spot_of(label: str) -> str:
    """The target spot a row's label names (``file:line:spot``), or the label itself (a spot of its own)."""
    spot = label.rsplit(":", 1)[-1]
    return spot if spot and spot != "row" else label


def contact_positions(model: ContactModel, contacts: Contacts) -> FloatArray:
    """Nominal contact point (x, y in m) of each row in its chain's sole frame. Shape (n, 2)."""
    out = np.zeros((len(contacts), 2))
    chains = np.array(contacts.chains)
    kinds = np.array([k.value for k in contacts.kinds])
    for name, chain in model.chains.items():
        for kind in set(contacts.kinds):
            rows = np.flatnonzero((chains == name) & (kinds == kind.value))
            if len(rows):
                placements = chain.nominal_placements()
                frames = chain.sole_to_contact(contacts.joints[rows], placements, np.zeros(3), kind)
                out[rows] = frames[:, :2, 3]
    return out


def balanced_regions(
    points: FloatArray, weights: NDArray[np.int_], k: int, rng: np.random.Generator
) -> NDArray[np.int_]:
    """Region of each point: k-means++ start, then assignments capped at ceil(sum(weights) / k). Shape (m,)."""
    k = min(k, len(points))
    centres = [points[rng.integers(len(points))]]
    for _ in range(k - 1):
        d2 = np.min([np.sum((points - c) ** 2, axis=1) for c in centres], axis=0) * weights
        centres.append(points[rng.choice(len(points), p=d2 / d2.sum())] if d2.sum() > 0 else points[len(centres)])
    centre = np.array(centres)
    capacity = np.ceil(weights.sum() / k)
    region = np.zeros(len(points), dtype=int)
    for _ in range(50):
        d2 = np.sum((points[:, None] - centre[None]) ** 2, axis=2)  # (m, k)
        region = -np.ones(len(points), dtype=int)
        load = np.zeros(k)
        for flat in np.argsort(d2, axis=None, kind="stable"):
            i, j = divmod(int(flat), k)
            if region[i] < 0 and load[j] + weights[i] <= capacity:
                region[i] = j
                load[j] += weights[i]
        for i in np.flatnonzero(region < 0):  # a spot heavier than what is left anywhere
            j = int(np.argmin(load))
            region[i] = j
            load[j] += weights[i]
        moved = np.array(
            [
                np.average(points[region == j], axis=0, weights=weights[region == j]) if np.any(region == j) else c
                for j, c in enumerate(centre)
            ]
        )
        if np.allclose(moved, centre):
            break
        centre = moved
    return region


def repeated_folds(model: ContactModel, contacts: Contacts, k: int, seeds: Sequence[int]) -> list[Fold]:
    """Every fold of every seed, chain by chain (sessions when a chain has several, else regions)."""
    positions = contact_positions(model, contacts)
    chains = np.array(contacts.chains)
    sessions = np.array(contacts.sessions)
    keys = np.array([f"{s}\x00{spot_of(lbl)}" for s, lbl in zip(contacts.sessions, contacts.labels, strict=True)])
    everything = np.arange(len(contacts))
    folds = []
    for seed in seeds:
        rng = np.random.default_rng([seed, 16])
        for chain in sorted(set(contacts.chains)):
            rows = np.flatnonzero(chains == chain)
            own = sorted(set(sessions[rows]))
            if len(own) > 1:
                groups = [rows[sessions[rows] == s] for s in own]
            else:
                spots = sorted(set(keys[rows]))
                members = [rows[keys[rows] == spot] for spot in spots]
                centre = np.array([positions[m].mean(axis=0) for m in members])
                region = balanced_regions(centre, np.array([len(m) for m in members]), k, rng)
                groups = [
                    np.concatenate([m for m, r in zip(members, region, strict=True) if r == j])
                    for j in sorted(set(region))
                ]
            for test in groups:
                train = np.setdiff1d(everything, test)
                held = tuple(int(i) for i in sorted(test))
                folds.append(Fold(seed, chain, tuple(int(i) for i in train), held, len(own) > 1))
    return folds
