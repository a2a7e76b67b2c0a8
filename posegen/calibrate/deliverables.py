"""What a robot loads: the files of a calibration, each chosen by what it can represent.

A URDF holds joint origins, not compliance. So a calibration ships:

* **the URDF alone** (:attr:`Deliverables.urdf`), for any stack (controllers, MoveIt,
  RViz, pinocchio): the rigid candidate (no compliance group) of lowest
  cross-validation score, fitted without compliance, so that its offsets do not lean
  on a sag the file cannot hold. When no rigid candidate scores better than the nominal
  URDF (contact offsets and planes fitted alike), the nominal URDF is kept, with a warning.
* **the URDF with its compensation** (:attr:`Deliverables.compensated`), for stacks that
  correct the encoder angles for the joints' give (``compliance.yaml``,
  :func:`posegen.calibrate.compensate`): the candidate of lowest score among all, when
  it has compliance; none when a rigid one scores best.

Both are scored by the same repeated grouped cross-validation as the model
(:mod:`posegen.calibrate.scoring`), so each file comes with its predicted held-out error.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass

from posegen.calibrate.estimation import Estimate
from posegen.calibrate.model_selection import NOMINAL, ModelSelection
from posegen.calibrate.scoring import CvResult, lowest_score
from posegen.robot import CandidateConfig


class DeliverableKind(str, enum.Enum):
    """Which stacks a deliverable serves."""

    URDF = "urdf"  # the URDF alone: any stack
    COMPENSATED = "compensated"  # the URDF and the compliance compensation of the encoder angles


@dataclass(frozen=True)
class Deliverable:
    """One set of files a robot loads, and what cross-validation predicts of it."""

    kind: DeliverableKind
    candidate: CandidateConfig  # NOMINAL when the URDF is kept as it was
    result: CvResult  # its cross-validation figures (predicted held-out error per chain)
    estimate: Estimate  # its fit on every kept training row

    @property
    def nominal(self) -> bool:
        """Whether this is the nominal URDF, kept."""
        return self.candidate.name == NOMINAL.name


@dataclass(frozen=True)
class Deliverables:
    """The URDF alone, and the URDF with its compensation when a compliant model predicts best."""

    urdf: Deliverable
    compensated: Deliverable | None
    warnings: tuple[str, ...]

    def all(self) -> tuple[Deliverable, ...]:
        """Every deliverable, the URDF alone first."""
        return (self.urdf,) if self.compensated is None else (self.urdf, self.compensated)


def choose_deliverables(selection: ModelSelection, candidates: Sequence[CandidateConfig]) -> Deliverables:
    """The deliverables of a model selection (see the module's docstring for the rule).

    Args:
        selection: Every candidate's cross-validation, and the nominal URDF's.
        candidates: The candidates tried (their compliance groups say what a URDF can hold).

    Example:
        >>> deliverables = choose_deliverables(calibration.selection, candidates)
        >>> deliverables.urdf.candidate.name, deliverables.urdf.result.score

    """
    by_name = {c.name: c for c in candidates}
    rigid_names = {c.name for c in candidates if not c.compliance}
    nominal = _deliverable(selection, DeliverableKind.URDF, NOMINAL, selection.nominal)
    warnings: list[str] = []
    rigid = lowest_score(selection.results, lambda r: r.candidate in rigid_names)
    if rigid is None:
        warnings.append("no rigid candidate model is plausible or configured: calibrated.urdf is the nominal URDF")
        urdf = nominal
    elif not rigid.score < selection.nominal.score:
        warnings.append(
            f"no rigid candidate predicts better than the nominal URDF (best {rigid.candidate} x{rigid.prior_scale:g}: "
            f"CV score {rigid.score:.1f} against {selection.nominal.score:.1f}): calibrated.urdf is the nominal URDF"
        )
        urdf = nominal
    else:
        urdf = _deliverable(selection, DeliverableKind.URDF, by_name[rigid.candidate], rigid)
    best = lowest_score(selection.results, lambda r: True)
    compensated = None
    if best is not None and by_name[best.candidate].compliance and best.score < urdf.result.score:
        compensated = _deliverable(selection, DeliverableKind.COMPENSATED, by_name[best.candidate], best)
    return Deliverables(urdf, compensated, tuple(warnings))


def _deliverable(
    selection: ModelSelection, kind: DeliverableKind, candidate: CandidateConfig, result: CvResult
) -> Deliverable:
    return Deliverable(kind, candidate, result, selection.estimates[result.candidate, result.prior_scale])
