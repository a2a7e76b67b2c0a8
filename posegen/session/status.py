"""Where a session stands: contacts so far, predicted error per chain over the batches, robot time."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from posegen.io import atomic_path, claim_output
from posegen.session.index import Batch, SessionIndex
from posegen.session.workflow import open_session

STATUS_PLOT = "status.png"


@dataclass(frozen=True)
class Status:
    """A session's figures (``posegen session status``)."""

    index: SessionIndex
    contacts: int  # measured so far
    spent_s: float  # robot time recorded so far (the bags' joint states)
    planned_s: float  # robot time of the routes still to play
    plot: Path | None  # the predicted error per chain over the batches (None: nothing assessed yet)

    @property
    def assessed(self) -> tuple[Batch, ...]:
        """The batches with a calibration figure, in order."""
        return tuple(b for b in self.index.batches if b.assessment is not None and not b.assessment.error)


def session_status(session: str, plot: str | None = None) -> Status:
    """A session's figures, and its plot (``SESSION/status.png`` unless ``plot`` names another file).

    Raises:
        PosegenError: Not a session, or a file of it changed by hand.

    """
    folder = Path(session)
    index = open_session(folder)
    contacts = sum(b.recording.contacts for b in index.batches if b.recording is not None)
    spent = sum(b.recording.duration_s for b in index.batches if b.recording is not None)
    planned = sum(b.planned_s for b in index.batches if b.recording is None)
    status = Status(index, contacts, spent, planned, None)
    if not status.assessed:
        return status
    path = Path(plot) if plot else folder / STATUS_PLOT
    with claim_output(path):
        _plot(status, path)
    return Status(index, contacts, spent, planned, path)


def _plot(status: Status, path: Path) -> None:
    """Predicted held-out height error per chain against the contacts measured, with the target."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    batches = status.assessed
    fig, ax = plt.subplots(figsize=(7, 4))
    chains = sorted({c for b in batches for c in b.assessment.predicted_z_mm} if batches else set())  # type: ignore[union-attr]
    for chain in chains:
        points = [
            (b.assessment.contacts, b.assessment.predicted_z_mm[chain])  # type: ignore[union-attr]
            for b in batches
            if chain in b.assessment.predicted_z_mm  # type: ignore[union-attr]
        ]
        ax.plot([p[0] for p in points], [p[1] for p in points], "o-", label=f"chain {chain}")
    target = status.index.settings.target_mm
    ax.axhline(target, color="tab:red", ls="--", label=f"target {target:g} mm")
    ax.set_xlabel("contacts measured")
    ax.set_ylabel("predicted held-out height error (mm, mean abs, grouped CV)")
    deliverable = status.index.settings.deliverable.value
    ax.set_title(f"session: predicted error of the {deliverable} deliverable after each batch")
    ax.legend()
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=100)
    plt.close(fig)
