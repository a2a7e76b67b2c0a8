"""A calibration folder's ``calibration.yaml`` as an object: :class:`CalibrationSummary`, its reader and writer.

The document (its sections in :mod:`posegen.calibrate.calibration_file`) is written as it is
built; the summary gives the fields a caller acts on typed (the files written with their
predicted and judged errors, the nominal URDF's, the interpretable model and its
figures, the rows left out), parsed from that same document, so what ``calibrate``
returns is what a reader of the file finds. The document is kept whole
(:attr:`CalibrationSummary.document`) for the viewer's sections (parameters, curves, planes).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from posegen.calibrate.deliverables import DeliverableKind
from posegen.errors import InputError, reason
from posegen.io import dump_yaml, read_yaml, write_atomic

CALIBRATION_FORMAT = "posegen-calibration"
CALIBRATION_VERSION = 3
COMPONENTS = ("z_mm", "roll_deg", "pitch_deg")  # residual components, as displayed
NOMINAL_KEY = "nominal_urdf"  # the nominal URDF's entry in the deliverables section (for comparison; not written)


@dataclass(frozen=True)
class Components:
    """A contact's three residual components, as displayed; None: no contact measures it (point contacts)."""

    z_mm: float  # every contact measures its height
    roll_deg: float | None
    pitch_deg: float | None

    def values(self) -> tuple[float, float | None, float | None]:
        """The components in the report's order (height, roll, pitch)."""
        return self.z_mm, self.roll_deg, self.pitch_deg


@dataclass(frozen=True)
class ErrorFigures:
    """Mean absolute and RMS of residuals (mm, deg)."""

    mean_abs: Components
    rms: Components


@dataclass(frozen=True)
class ChosenModel:
    """The model the calibration fitted."""

    candidate: str
    fit: tuple[str, ...]  # parameter patterns fitted
    floor_equations: bool
    compliance: tuple[str, ...]  # compliance groups fitted
    prior_scale: float  # x calibration.prior of the config


@dataclass(frozen=True)
class CvFigures:
    """A (candidate, prior scale) pair's repeated cross-validation."""

    candidate: str
    prior_scale: float
    free_parameters: int
    score: float
    se: float  # standard error of the score


@dataclass(frozen=True)
class SetFigures:
    """Some contacts' residuals as a stack loading a file sees them: their number, mean absolute and RMS."""

    contacts: int
    mean_abs: Components
    rms: Components


@dataclass(frozen=True)
class FileFigures:
    """What is known of a file's error (mm, deg), per chain: predicted by cross-validation, and judged.

    ``training`` and ``held_out`` hold ``"all"`` (every chain) and each chain; judged as a
    stack loading the file sees it (:data:`posegen.calibrate.file_judge.JUDGED_AS`).
    """

    predicted_error: dict[str, ErrorFigures]  # by chain: grouped CV
    training: dict[str, SetFigures]  # the kept training rows
    held_out: dict[str, SetFigures]  # empty without held-out files


@dataclass(frozen=True)
class DeliverableSummary:
    """One set of files a robot loads, its model and its figures."""

    kind: DeliverableKind
    files: tuple[str, ...]  # relative to the calibration folder, the URDF first
    candidate: str
    prior_scale: float
    figures: FileFigures

    @property
    def predicted_error(self) -> dict[str, ErrorFigures]:
        """By chain: the held-out error cross-validation predicts for these files."""
        return self.figures.predicted_error


@dataclass(frozen=True)
class LeftOutRow:
    """A training row the robust screening flagged."""

    file: str
    line: str
    spot: str
    reason: str
    value: float  # studentised residual or offset
    kept: bool  # flagged but kept in the fit (--keep-outliers)


@dataclass(frozen=True)
class CalibrationSummary:
    """What ``calibration.yaml`` says: the files written and their errors, the interpretable model, the rows left out.

    Example:
        >>> summary = posegen.load("plans/calibration")  # the folder calibrate wrote
        >>> summary.deliverables[DeliverableKind.URDF].figures.held_out["left"].mean_abs.z_mm  # as a stack sees it

    """

    document: dict[str, Any]  # the file's content, as written
    provenance: dict[str, Any]  # config, robot model hash, seed, posegen version
    deliverables: dict[DeliverableKind, DeliverableSummary]  # the files written, the URDF alone first
    nominal: FileFigures  # the nominal URDF, judged alike (for comparison; not written)
    model: ChosenModel  # the interpretable model (one-SE rule): not a file
    model_figures: FileFigures  # its CV-predicted error, and its fit judged as the files are
    chosen: CvFigures  # the interpretable model's cross-validation
    stability: float  # share of the fold seeds that pick the chosen pair
    contact_noise: Components  # fitted contact noise
    warnings: tuple[str, ...]
    left_out: tuple[LeftOutRow, ...]
    rejected_rows: tuple[str, ...]  # input rows not usable, one message each

    @property
    def predicted_error(self) -> dict[str, ErrorFigures]:
        """By chain: the interpretable model's CV-predicted held-out error (a file's: its own figures)."""
        return self.model_figures.predicted_error


def write_summary(path: str | Path, summary: CalibrationSummary) -> None:
    """Write ``calibration.yaml``, atomically."""
    write_atomic(path, dump_yaml(summary.document))


def read_summary(path: str | Path) -> CalibrationSummary:
    """Read a ``calibration.yaml``.

    Raises:
        InputError: The file is missing, not a calibration, or malformed.

    """
    return summary_from_dict(read_yaml(path, CALIBRATION_FORMAT), str(path))


def summary_from_dict(document: dict[str, Any], where: str = "calibration") -> CalibrationSummary:
    """Parse plain data in the ``calibration.yaml`` format.

    Raises:
        InputError: Not a calibration of this format version, or malformed.

    """
    version = document.get("format_version")
    if version != CALIBRATION_VERSION or isinstance(version, bool):
        raise InputError(f"{where}: unsupported format_version {version!r} (this posegen reads {CALIBRATION_VERSION})")
    try:
        model, selection, files = document["model"], document["model_selection"], document["deliverables"]
        chosen = selection["chosen"]
        if not isinstance(document["provenance"], dict):
            raise TypeError("provenance must be a mapping")
        return CalibrationSummary(
            document=document,
            provenance=dict(document["provenance"]),
            deliverables={
                kind: _deliverable(kind, files[kind.value]) for kind in DeliverableKind if kind.value in files
            },
            nominal=_figures(files[NOMINAL_KEY]),
            model=ChosenModel(
                str(model["candidate"]),
                tuple(str(p) for p in model["fit"]),
                bool(model["floor_equations"]),
                tuple(str(g) for g in model["compliance"]),
                float(model["prior_scale"]),
            ),
            model_figures=_figures(model),
            chosen=CvFigures(
                str(chosen["candidate"]),
                float(chosen["prior_scale"]),
                int(chosen["free_parameters"]),
                float(chosen["score"]),
                float(chosen["se"]),
            ),
            stability=float(selection["stability"]["share_of_seeds"]),
            contact_noise=_components(document["noise"]["contact"]),
            warnings=tuple(str(w) for w in document["warnings"]),
            left_out=tuple(_left_out(row) for row in document["left_out"]),
            rejected_rows=tuple(str(r) for r in document["rejected_rows"]),
        )
    except (KeyError, TypeError, ValueError, AttributeError, OverflowError) as exc:
        raise InputError(f"{where}: not a posegen calibration ({reason(exc)})") from exc


def _number(value: Any) -> float | None:
    return None if value is None else float(value)


def _components(raw: dict[str, Any]) -> Components:
    """Height, roll, pitch errors; a height written as null (a file no cross-validation scored) reads as nan."""
    z, roll, pitch = COMPONENTS
    return Components(float("nan") if raw[z] is None else float(raw[z]), _number(raw[roll]), _number(raw[pitch]))


def _errors(raw: dict[str, Any]) -> ErrorFigures:
    return ErrorFigures(_components(raw["mean_abs"]), _components(raw["rms"]))


def _by_chain(raw: dict[str, Any]) -> dict[str, ErrorFigures]:
    return {str(chain): _errors(e) for chain, e in dict(raw).items()}


def _sets(raw: dict[str, Any]) -> dict[str, SetFigures]:
    return {
        str(name): SetFigures(int(e["contacts"]), _components(e["mean_abs"]), _components(e["rms"]))
        for name, e in dict(raw).items()
    }


def _figures(raw: dict[str, Any]) -> FileFigures:
    return FileFigures(_by_chain(raw["predicted_error"]), _sets(raw["training"]), _sets(raw.get("held_out") or {}))


def _deliverable(kind: DeliverableKind, raw: dict[str, Any]) -> DeliverableSummary:
    return DeliverableSummary(
        kind, tuple(str(f) for f in raw["files"]), str(raw["candidate"]), float(raw["prior_scale"]), _figures(raw)
    )


def _left_out(raw: dict[str, Any]) -> LeftOutRow:
    return LeftOutRow(
        str(raw["file"]), str(raw["line"]), str(raw["spot"]), str(raw["reason"]), float(raw["value"]), bool(raw["kept"])
    )
