"""What a calibration run writes: report YAML, residual tables, plots, calibrated URDF.

Output folder::

    calibration.yaml     the files written and their errors first, then the interpretable model, model
                         selection, rows left out, noise, parameters, provenance
    residuals.csv        every contact's residuals under the nominal URDF and calibrated.urdf, as a stack
                         loading each sees them, and its joint angles
    posterior.npz        posterior covariance of the fitted directions, conditioning of their regressor
    calibrated.urdf      the URDF alone: any stack loads it (same links and joints, calibrated origins;
                         a <link>_mount where a sole or gripper is a moving joint's link)
    calibrated.yaml      a scene config that uses calibrated.urdf
    offsets.yaml         calibrated.urdf as joint angle offsets and placement changes of the nominal URDF
    with_compliance/     the URDF, compliance.yaml and offsets.yaml of a compliant model, when one predicts best
                         (:mod:`posegen.calibrate.deliverable_files`)
    parameters.png       the interpretable model's fitted deviations (mm, deg)
    residuals.png        held-out residuals, nominal URDF and calibrated.urdf (or training ones without held-out data)
    cross_validation.png CV score of every candidate over the prior scale
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from posegen.calibrate.calibration import Calibration
from posegen.calibrate.deliverable_files import (
    Judgements,
    deliverables_report,
    file_entry,
    judge_all,
    predicted_figures,
    write_deliverable,
)
from posegen.calibrate.deliverables import DeliverableKind
from posegen.calibrate.plots import Plot, draw_all
from posegen.calibrate.record import CALIBRATION_FILE, CALIBRATION_FORMAT, COMPONENTS, DISPLAY, write_record
from posegen.calibrate.scoring import RULE, CvResult
from posegen.calibrate.summary import CALIBRATION_VERSION, CalibrationSummary, summary_from_dict, write_summary
from posegen.calibrate.summary_text import SHORT
from posegen.model import FLOOR_FIELDS, OFFSET_FIELDS, SESSION_FIELDS, Contacts, Kind, Parameter, kind_sigmas
from posegen.robot import FloatArray

LENGTH_KINDS = (Kind.LINK_TRANSLATION, Kind.CONTACT_HEIGHT, Kind.CONTACT_POINT)
MODEL_ROLE = (
    "the interpretable model: the one-standard-error rule's pick among the candidates (what this robot's physics "
    "shows, and what a follow-up design plans for); not a file a robot loads: see deliverables"
)


def _shown(values: Sequence[float] | FloatArray, digits: int = 4) -> dict[str, float | None]:
    """Components in mm and deg; None for a component no contact measures (roll, pitch of point contacts)."""
    return {
        c: round(float(v), digits) if np.isfinite(v) else None
        for c, v in zip(COMPONENTS, np.asarray(values, dtype=float) * DISPLAY, strict=True)
    }


def _display(kind: Kind) -> tuple[str, float]:
    if kind in LENGTH_KINDS:
        return "mm", 1e3
    if kind == Kind.COMPLIANCE:
        return "rad/kNm", 1e3
    return "deg", float(np.degrees(1.0))


def parameter_table(calibration: Calibration) -> list[dict[str, Any]]:
    """Every fitted direction but planes and floor constants: deviation and posterior std (mm, deg, rad/kNm)."""
    rows = []
    for i in calibration.spec.free:
        d = calibration.model.directions[i]
        if d.kind in (Kind.PLANE, Kind.FLOOR):
            continue
        unit, scale = _display(d.kind)
        rows.append(
            {
                "name": d.name,
                "kind": d.kind.value,
                "part": d.part.value,
                "unit": unit,
                "deviation": round(float(calibration.after.delta[i] * scale), 5),
                "std": round(float(calibration.after.std[i] * scale), 5),
            }
        )
    return rows


def _cv_row(result: CvResult) -> dict[str, Any]:
    return {
        "candidate": result.candidate,
        "prior_scale": result.prior_scale,
        "free_parameters": result.free,
        "score": round(result.score, 2),
        "se": round(result.se, 2),
        "chains": {c: _shown(e.mean_abs, 3) for c, e in result.chains.items()},
        "largest_deviation": {"mm": round(result.largest[0], 2), "deg": round(result.largest[1], 3)},
        "plausible": result.plausible,
    }


def selection_report(calibration: Calibration) -> dict[str, Any]:
    """The candidates' ranking, every CV point, the chosen pair and how stable it is over the seeds."""
    selection = calibration.selection
    by_candidate: dict[str, list[CvResult]] = {}
    for r in selection.results:
        by_candidate.setdefault(r.candidate, []).append(r)
    ranking = sorted((min(rs, key=lambda r: r.score) for rs in by_candidate.values()), key=lambda r: r.score)
    implausible = [r for r in selection.results if not r.plausible]
    config = calibration.config
    return {
        "rule": RULE,
        "folds": {"per_chain": config.folds, "seeds": config.fold_seeds, "fold_iterations": config.fold_iterations},
        "chosen": _cv_row(selection.chosen),
        "best": _cv_row(selection.best),
        "stability": {
            "share_of_seeds": round(selection.stability, 3),
            "picks": [{"candidate": c, "prior_scale": s} for c, s in selection.seed_picks],
        },
        "ranking": [_cv_row(r) for r in ranking],
        "implausible": [
            {
                "candidate": r.candidate,
                "prior_scale": r.prior_scale,
                "mm": round(r.largest[0], 1),
                "deg": round(r.largest[1], 2),
            }
            for r in implausible
        ],
        "curves": {
            name: [
                {"prior_scale": r.prior_scale, "score": round(r.score, 2), "se": round(r.se, 2)}
                for r in rs
                if r.plausible
            ]
            for name, rs in by_candidate.items()
        },
    }


def target_warnings(calibration: Calibration) -> list[str]:
    """A warning per chain that no file written is predicted to meet ``calibration.target_error_mm`` on (height)."""
    target = calibration.config.target_error_mm
    warnings = []
    for chain in sorted(calibration.model.contact.chains):
        predicted = {  # file -> its CV-predicted height error on this chain, mm
            SHORT[d.kind]: d.result.chains[chain].mean_abs[0] * 1e3
            for d in calibration.deliverables.all()
            if chain in d.result.chains
        }
        if predicted and min(predicted.values()) > target:
            shown = ", ".join(f"{name} {z:.2f} mm" for name, z in predicted.items())
            warnings.append(
                f"chain '{chain}': predicted held-out height error above the target {target:g} mm ({shown}); "
                "record more contacts of this chain (posegen select POOL --given ...)"
            )
    return warnings


def left_out_rows(calibration: Calibration) -> list[dict[str, Any]]:
    """Rows left out: file, line, target spot, why, and the residual (studentised) or offset."""
    out = []
    for flag in calibration.flags:
        file, _, rest = flag.label.partition(":")
        line, _, spot = rest.partition(":")
        out.append(
            {
                "file": file,
                "line": line,
                "spot": spot,
                "reason": flag.reason,
                "value": round(flag.value, 3),
                "round": flag.round,
                "kept": flag.row in calibration.kept,
            }
        )
    return out


def _noise(calibration: Calibration) -> dict[str, Any]:
    noise = calibration.after.noise
    out: dict[str, Any] = {"contact": _shown(noise.contact)}
    if calibration.spec.floor:
        scale = np.array([1e3, 1e3, 1e3, *([float(np.degrees(1.0))] * 3)])
        units = ("x_mm", "y_mm", "z_mm", "roll_deg", "pitch_deg", "yaw_deg")
        out["floor"] = {u: round(float(v), 5) for u, v in zip(units, np.array(noise.floor) * scale, strict=True)}
        assert len(units) == len(FLOOR_FIELDS)
    return out


def calibration_report(
    calibration: Calibration,
    held_out: Contacts | None,
    seed: int | None,
    rejected_rows: Sequence[str],
    judged: Judgements,
) -> dict[str, Any]:
    """The content of calibration.yaml: the files written and their errors first."""
    model = calibration.model
    x = calibration.after.x
    sigmas = kind_sigmas(calibration.config.prior)
    scale = calibration.selection.chosen.prior_scale
    report: dict[str, Any] = {
        "format": CALIBRATION_FORMAT,
        "format_version": CALIBRATION_VERSION,
        "deliverables": deliverables_report(calibration, judged, held_out),
        "provenance": model.scene.provenance(seed),
        "chains": sorted(model.contact.chains),
        "sessions": list(model.sessions),
        "model": {
            "role": MODEL_ROLE,
            "candidate": calibration.candidate.name,
            "fit": list(calibration.candidate.fit),
            "floor_equations": calibration.spec.floor,
            "compliance": list(calibration.candidate.compliance),
            "prior_scale": scale,
            "prior_sigma": {
                k.value: round(float(v * scale * _display(k)[1]), 5) for k, v in sigmas.items() if np.isfinite(v)
            },
            "predicted_error": predicted_figures(calibration.selection.chosen),
            **file_entry(calibration, judged.model, held_out),
        },
        "warnings": [*calibration.warnings, *target_warnings(calibration)],
        "model_selection": selection_report(calibration),
        "noise": _noise(calibration),
        "left_out": left_out_rows(calibration),
        "rejected_rows": list(rejected_rows),
        "base_parameters": {
            "contacts": calibration.base.size,
            "contacts_and_floor": calibration.base_with_floor,
            "parameters": calibration.model.contact.size,
            "note": "QR of the regressor at postures shaped like the training ones (identifiability only; the fit "
            "regularises every parameter by its prior)",
        },
        "compliance": {
            group: {
                "joints": [model.scene.joint_names[j] for j in model.compliance[group]],
                "rad_per_knm": round(value * 1e3, 5),
            }
            for group, value in model.compliances(x).items()
            if group in calibration.candidate.compliance
        },
        "planes": {
            s: {f: float(x[model.contact.column(Parameter.plane(s, f))]) for f in OFFSET_FIELDS} for s in model.sessions
        },
        "parameters": parameter_table(calibration),
    }
    if calibration.spec.floor:
        report["floor"] = {
            s: dict(zip(SESSION_FIELDS, (float(v) for v in x[model.floor_columns(s)]), strict=True))
            for s in sorted(set(calibration.train.subset(list(calibration.kept)).sessions))
        }
    return report


def write_calibration(
    calibration: Calibration,
    held_out: Contacts | None,
    out_dir: Path,
    seed: int | None,
    rejected_rows: Sequence[str] = (),
) -> CalibrationSummary:
    """Write every output of a calibration into ``out_dir`` and return its ``calibration.yaml``.

    The deliverables' files are written first, then read back and judged as a stack
    loading them sees them (:mod:`posegen.calibrate.file_judge`): the figures every
    other file and the command print are those.

    Args:
        calibration: The calibration.
        held_out: Held-out contacts, if any.
        out_dir: Output folder (created).
        seed: Seed recorded in the provenance.
        rejected_rows: Input rows left out as unusable, one message each.

    """
    summary, plots = write_calibration_files(calibration, held_out, out_dir, seed, rejected_rows)
    draw_all(plots)
    return summary


def write_calibration_files(
    calibration: Calibration,
    held_out: Contacts | None,
    out_dir: Path,
    seed: int | None,
    rejected_rows: Sequence[str] = (),
) -> tuple[CalibrationSummary, list[Plot]]:
    """:func:`write_calibration` but for its plots: the summary, and the plots still to draw (:func:`drawing`)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    written = [write_deliverable(calibration, d, out_dir, seed) for d in calibration.deliverables.all()]
    judged = judge_all(calibration, written, held_out)
    report = calibration_report(calibration, held_out, seed, rejected_rows, judged)
    summary = summary_from_dict(report, str(out_dir / CALIBRATION_FILE))
    shown = [r for r in report["parameters"] if r["unit"] in ("mm", "deg")]
    chosen = calibration.selection.chosen
    curves = report["model_selection"]["curves"]
    plots = [
        Plot("parameters", (shown,), out_dir / "parameters.png"),
        Plot("cross_validation", (curves, (chosen.candidate, chosen.prior_scale)), out_dir / "cross_validation.png"),
    ]
    nominal, urdf = judged.nominal, judged.files[DeliverableKind.URDF]
    if held_out is not None and nominal.held_out is not None and urdf.held_out is not None:
        title = "Held-out residuals (plane from training): nominal URDF and calibrated.urdf"
        plots.append(Plot("residuals", (nominal.held_out, urdf.held_out, title), out_dir / "residuals.png"))
    else:
        kept = list(calibration.kept)
        title = "Training residuals: nominal URDF and calibrated.urdf"
        residuals = (nominal.training[kept], urdf.training[kept], title)
        plots.append(Plot("residuals", residuals, out_dir / "residuals.png"))
    write_record(calibration, held_out, out_dir, (nominal, urdf))
    write_summary(out_dir / CALIBRATION_FILE, summary)
    return summary, plots
