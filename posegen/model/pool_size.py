"""How many contact postures a robot's pool needs to identify its base parameters.

A contact measures ``rows`` numbers (3 flush: height, roll, pitch; 1 point: height), so a
chain of ``nb`` base parameters needs at least ``ceil(nb / rows)`` contacts: no selection
of fewer, and no pool of fewer, can identify them. A pool's postures are not independent
(a table, a stance, limits): it needs more than that minimum. ``POOL_FACTOR`` times the
minimum is what posegen recommends: on TALOS (flush, 2 x 57 base parameters, minimum 38)
the example pool first identified every parameter at 70 postures, 1.8 times the minimum.

Example:
    >>> size = pool_size(scene)
    >>> size.minimum, size.recommended  # postures: (38, 152) on TALOS

"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from posegen.model.contact_model import ContactModel, Contacts, planned_kinds
from posegen.model.contact_rows import row_counts
from posegen.model.structural import structural_base
from posegen.robot import Scene

POOL_FACTOR = 4  # a pool this many times the minimum: twice what TALOS's example pool needed
SESSION = "s"


@dataclass(frozen=True)
class PoolSize:
    """The postures a pool of this robot needs."""

    base_parameters: dict[str, int]  # per chain, of its planned contact kind
    rows: dict[str, int]  # per chain, numbers one contact measures
    minimum: int  # postures below which no pool identifies every base parameter

    @property
    def recommended(self) -> int:
        """The pool size posegen recommends (``POOL_FACTOR`` times the minimum)."""
        return POOL_FACTOR * self.minimum

    def describe(self) -> str:
        """One line: the base parameters, the minimum and the recommended pool."""
        chains = ", ".join(f"{c} {n} ({self.rows[c]} per contact)" for c, n in self.base_parameters.items())
        return (
            f"a pool needs at least {self.minimum} postures to identify the base parameters (per chain: "
            f"{chains}); sample a pool of {self.recommended} or more"
        )


def minimum_postures(base_parameters: int, rows: int) -> int:
    """The fewest contacts of ``rows`` numbers that can identify ``base_parameters``."""
    return math.ceil(base_parameters / max(rows, 1))


def pool_size(scene: Scene) -> PoolSize:
    """The base parameters of each chain (generic standing contacts at the reference) and the pool they need.

    Raises:
        InfeasibleError: No standing contact can be generated around the reference posture.

    """
    counts: dict[str, int] = {}
    rows: dict[str, int] = {}
    for chain in scene.config.chains:
        kinds = planned_kinds(scene, (chain.name,))
        contacts = Contacts(scene.reference[None, :].copy(), (chain.name,), (SESSION,), ("",), kinds)
        model = ContactModel(scene, [chain.name], [SESSION], contacts.kinds_by_chain())
        counts[chain.name] = len(structural_base(model, contacts).columns)
        rows[chain.name] = int(row_counts(kinds)[0])
    minimum = int(np.sum([minimum_postures(counts[c], rows[c]) for c in counts]))
    return PoolSize(counts, rows, minimum)
