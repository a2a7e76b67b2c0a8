"""A calibration's summary as the lines a command prints: the files first, then the interpretable model.

Every figure printed is one of ``calibration.yaml`` (:class:`CalibrationSummary`), rounded
for the eye: a file's CV-predicted error and its error as a stack loading it sees it
(:mod:`posegen.calibrate.file_judge`), so one thing has one number everywhere
(``posegen calibrate``, ``posegen session``, the report).
"""

from __future__ import annotations

import math

from posegen.calibrate.deliverables import DeliverableKind
from posegen.calibrate.model_selection import NOMINAL as NOMINAL_CANDIDATE
from posegen.calibrate.summary import CalibrationSummary, Components, DeliverableSummary, FileFigures, SetFigures

COMPLIANT_DIR = "with_compliance"
COMPLIANCE_FILE = "compliance.yaml"
SHORT = {DeliverableKind.URDF: "calibrated.urdf", DeliverableKind.COMPENSATED: f"{COMPLIANT_DIR}/"}
WHO = {DeliverableKind.URDF: "any stack", DeliverableKind.COMPENSATED: "stacks that compensate compliance"}
NOMINAL = "nominal URDF"


def _triple(values: Components) -> str:
    return " / ".join("-" if v is None else f"{v:.2f}" for v in values.values())


def _by_chain(figures: dict[str, Components], counts: dict[str, int] | None = None) -> str:
    parts = []
    for chain, values in sorted(figures.items()):
        count = f" ({counts[chain]} contacts)" if counts else ""
        parts.append(f"{chain} {_triple(values)}{count}")
    return ", ".join(parts)


def figure_lines(figures: FileFigures, indent: str = "    ") -> list[str]:
    """A file's CV-predicted error per chain and, with held-out contacts, its held-out error per chain."""
    predicted = {c: e.mean_abs for c, e in figures.predicted_error.items()}
    if all(math.isnan(e.z_mm) for e in predicted.values()):  # left out of the rules: its fit is implausible
        lines = [f"{indent}predicted held-out (grouped CV)  not scored: its fit on every row is implausible"]
    else:
        lines = [f"{indent}predicted held-out (grouped CV)  {_by_chain(predicted)}"]
    held = {c: s for c, s in figures.held_out.items() if c != "all"}
    if held:
        shown = _by_chain({c: s.mean_abs for c, s in held.items()}, {c: s.contacts for c, s in held.items()})
        lines.append(f"{indent}held-out (plane from training)   {shown}")
    return lines


def file_lines(summary: CalibrationSummary) -> list[str]:
    """Each file written (its model, who loads it, its figures), then the nominal URDF's, for comparison."""
    lines = []
    for kind, deliverable in summary.deliverables.items():
        lines.append(f"  {SHORT[kind]} ({WHO[kind]}; {_model(deliverable)}):")
        lines.extend(figure_lines(deliverable.figures))
    lines.append(f"  the {NOMINAL} (for comparison; not written):")
    lines.extend(figure_lines(summary.nominal))
    return lines


def _model(deliverable: DeliverableSummary) -> str:
    if deliverable.candidate == NOMINAL_CANDIDATE.name:
        return "the nominal URDF, kept"
    return f"{deliverable.candidate} x{deliverable.prior_scale:g}"


def model_line(summary: CalibrationSummary) -> str:
    """The interpretable model: how it was chosen, and its CV-predicted error (it is not a file)."""
    chosen = summary.chosen
    predicted = {c: e.mean_abs for c, e in summary.model_figures.predicted_error.items()}
    return (
        f"interpretable model (one-standard-error rule; not a file): {summary.model.candidate} x"
        f"{summary.model.prior_scale:g} ({chosen.free_parameters} free parameters, CV score {chosen.score} +- "
        f"{chosen.se}; picked by {summary.stability:.0%} of the fold seeds); predicted held-out {_by_chain(predicted)}"
    )


def _cell(value: float | None) -> str:
    return f"{value:>7.2f}" if value is not None else f"{'-':>7}"


def _row(label: str, chain: str, name: str, figures: SetFigures) -> str:
    cells = "".join(
        f"{_cell(m)}{_cell(r)}" for m, r in zip(figures.mean_abs.values(), figures.rms.values(), strict=True)
    )
    return f"{label:<10}{chain:<8}{name:<18}{figures.contacts:>8}  {cells}"


def format_table(summary: CalibrationSummary) -> str:
    """Every file's errors as a stack loading it sees them, per set and chain (mean absolute; RMS)."""
    lines = [
        "set       chain   file              contacts    z (mm)        roll (deg)    pitch (deg)",
        "                                                mean   rms    mean   rms    mean   rms",
    ]
    files = [(NOMINAL, summary.nominal)] + [(SHORT[k], d.figures) for k, d in summary.deliverables.items()]
    for label, attribute in (("training", "training"), ("held-out", "held_out")):
        chains = sorted(c for c in getattr(summary.nominal, attribute) if c != "all")
        for chain in chains:
            for name, figures in files:
                lines.append(_row(label, chain, name, getattr(figures, attribute)[chain]))
    return "\n".join(lines)


def load_line(summary: CalibrationSummary) -> str:
    """One line: which file to load for which stack, with each one's predicted held-out height error."""
    parts = []
    for kind, deliverable in summary.deliverables.items():
        errors = ", ".join(
            f"{chain} {e.mean_abs.z_mm:.2f} mm" for chain, e in sorted(deliverable.predicted_error.items())
        )
        what = deliverable.files[0] if kind == DeliverableKind.URDF else f"{COMPLIANT_DIR}/ (URDF + {COMPLIANCE_FILE})"
        parts.append(f"{what} for {WHO[kind]} (predicted held-out z {errors})")
    return "load: " + "; or ".join(parts)
