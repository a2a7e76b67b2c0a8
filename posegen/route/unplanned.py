"""Why a stop or a transfer of a route has no plan: a typed result, said in the words a route file records.

A planning job (:mod:`posegen.route.planner`) returns its stop or transfer, or an
:class:`Unplanned`; the route then places the posture elsewhere, substitutes it, or skips
it with that reason (``str(unplanned)``, the text the route file keeps).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass


class UnplannedCause(str, enum.Enum):
    """What blocked a stop or a transfer."""

    NO_VERTICAL = "no balanced, collision-free vertical approach above the contact"  # a stop
    NO_FREE_MOTION = "no free motion"  # a transfer: straight line, vias and OMPL all failed
    NO_TIMING = "no time parameterisation of the planned path"  # toppra found none (a stop or a transfer)
    TORQUE = "the go-to-contact exceeds the effort limits pressing the contact force"  # a stop


@dataclass(frozen=True)
class Unplanned:
    """A stop or a transfer that could not be planned."""

    cause: UnplannedCause
    detail: str = ""  # what was tried, in words (the budgets of the attempt)

    def __str__(self) -> str:
        return f"{self.cause.value}: {self.detail}" if self.detail else self.cause.value
