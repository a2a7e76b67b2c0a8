"""What a calibration run writes: report YAML, residual tables, plots, calibrated URDF.

Output folder::

    calibration.yaml     model selection, predicted error, rows left out, noise, parameters, residuals, provenance
    residuals.csv        every contact's residuals before and after, and its joint angles
    posterior.npz        posterior covariance of the fitted directions, conditioning of their regressor
    calibrated.urdf      the URDF alone: any stack loads it (same links and joints, calibrated origins;
                         a <link>_mount where a sole or gripper is a moving joint's link)
    calibrated.yaml      a scene config that uses calibrated.urdf
    offsets.yaml         calibrated.urdf as joint angle offsets and placement changes of the nominal URDF
    with_compliance/     the URDF, compliance.yaml and offsets.yaml of a compliant model, when one predicts best
                         (:mod:`posegen.calibrate.deliverable_files`)
    parameters.png       fitted deviations (mm, deg)
    residuals.png        held-out residuals before/after (or training ones without held-out data)
    cross_validation.png CV score of every candidate over the prior scale
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from posegen.calibrate.calibration import Calibration, held_out_residuals
from posegen.calibrate.deliverable_files import deliverables_report, write_deliverable
from posegen.calibrate.plots import plot_cross_validation, plot_parameters, plot_residuals
from posegen.calibrate.record import CALIBRATION_FILE, CALIBRATION_FORMAT, COMPONENTS, DISPLAY, write_record
from posegen.calibrate.scoring import RULE, CvResult, column_stats
from posegen.calibrate.summary import CalibrationSummary, summary_from_dict, write_summary
from posegen.model import FLOOR_FIELDS, OFFSET_FIELDS, SESSION_FIELDS, Contacts, Kind, Parameter, kind_sigmas, masked
from posegen.robot import ContactKind, FloatArray

LENGTH_KINDS = (Kind.LINK_TRANSLATION, Kind.CONTACT_HEIGHT, Kind.CONTACT_POINT)


def _shown(values: Sequence[float] | FloatArray, digits: int = 4) -> dict[str, float | None]:
    """Components in mm and deg; None for a component no contact measures (roll, pitch of point contacts)."""
    return {
        c: round(float(v), digits) if np.isfinite(v) else None
        for c, v in zip(COMPONENTS, np.asarray(values, dtype=float) * DISPLAY, strict=True)
    }


def residual_stats(residuals: FloatArray, kinds: Sequence[ContactKind]) -> dict[str, dict[str, float | None]]:
    """RMS and mean absolute of (n, 3) residuals over the rows the contacts (of these kinds) measure, mm and deg."""
    mean_abs, rms = column_stats(masked(residuals, kinds))
    return {"mean_abs": _shown(mean_abs), "rms": _shown(rms)}


def residual_tables(calibration: Calibration, held_out: Contacts | None) -> dict[str, Any]:
    """Training and held-out residual statistics, before and after."""
    model = calibration.model
    observations = model.observations(calibration.train.subset(list(calibration.kept)))
    kinds = observations.contacts.kinds
    training = {
        name: residual_stats(model.evaluate(fitted.x, observations, floor=False).contact, kinds)
        for name, fitted in (("before", calibration.before), ("after", calibration.after))
    }
    tables: dict[str, Any] = {"training": {**training, "contacts": len(observations)}}
    if held_out is not None:
        for protocol, by_model in held_out_residuals(calibration, held_out).items():
            tables[f"held_out_{protocol}"] = {k: residual_stats(v, held_out.kinds) for k, v in by_model.items()}
            tables[f"held_out_{protocol}"]["contacts"] = len(held_out)
    return tables


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


def predicted_error(calibration: Calibration) -> tuple[dict[str, Any], list[str]]:
    """The chosen model's CV-predicted held-out error per chain, and warnings above the target."""
    target = calibration.config.target_error_mm
    out, warnings = {}, []
    for chain, error in calibration.selection.chosen.chains.items():
        z_mm = error.mean_abs[0] * 1e3
        out[chain] = {"mean_abs": _shown(error.mean_abs, 3), "rms": _shown(error.rms, 3), "above_target": z_mm > target}
        if z_mm > target:
            warnings.append(
                f"chain '{chain}': predicted held-out height error {z_mm:.2f} mm is above the target {target:g} mm; "
                f"record more contacts of this chain (posegen select POOL --given ...)"
            )
    return out, warnings


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
    calibration: Calibration, held_out: Contacts | None, seed: int | None, rejected_rows: Sequence[str]
) -> dict[str, Any]:
    """The content of calibration.yaml."""
    model = calibration.model
    x = calibration.after.x
    predicted, warnings = predicted_error(calibration)
    sigmas = kind_sigmas(calibration.config.prior)
    scale = calibration.selection.chosen.prior_scale
    report: dict[str, Any] = {
        "format": CALIBRATION_FORMAT,
        "format_version": 2,
        "provenance": model.scene.provenance(seed),
        "chains": sorted(model.contact.chains),
        "sessions": list(model.sessions),
        "model": {
            "candidate": calibration.candidate.name,
            "fit": list(calibration.candidate.fit),
            "floor_equations": calibration.spec.floor,
            "compliance": list(calibration.candidate.compliance),
            "prior_scale": scale,
            "prior_sigma": {
                k.value: round(float(v * scale * _display(k)[1]), 5) for k, v in sigmas.items() if np.isfinite(v)
            },
        },
        "predicted_error": predicted,
        "warnings": [*calibration.warnings, *warnings],
        "deliverables": deliverables_report(calibration, held_out),
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
        "residuals": residual_tables(calibration, held_out),
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

    Args:
        calibration: The calibration.
        held_out: Held-out contacts, if any.
        out_dir: Output folder (created).
        seed: Seed recorded in the provenance.
        rejected_rows: Input rows left out as unusable, one message each.

    """
    out_dir.mkdir(parents=True, exist_ok=True)
    report = calibration_report(calibration, held_out, seed, rejected_rows)
    summary = summary_from_dict(report, str(out_dir / CALIBRATION_FILE))
    for deliverable in calibration.deliverables.all():
        write_deliverable(calibration, deliverable, out_dir, seed)
    plot_parameters([r for r in report["parameters"] if r["unit"] in ("mm", "deg")], out_dir / "parameters.png")
    chosen = calibration.selection.chosen
    plot_cross_validation(
        report["model_selection"]["curves"], (chosen.candidate, chosen.prior_scale), out_dir / "cross_validation.png"
    )
    model = calibration.model
    if held_out is not None:
        res = held_out_residuals(calibration, held_out)["training_plane"]
        title = "Held-out residuals (plane from training)"
        kinds = held_out.kinds  # a point contact's roll and pitch (not measured) are not drawn
        plot_residuals(masked(res["before"], kinds), masked(res["after"], kinds), title, out_dir / "residuals.png")
    else:
        observations = model.observations(calibration.train.subset(list(calibration.kept)))
        kinds = observations.contacts.kinds
        plot_residuals(
            masked(model.evaluate(calibration.before.x, observations, floor=False).contact, kinds),
            masked(model.evaluate(calibration.after.x, observations, floor=False).contact, kinds),
            "Training residuals",
            out_dir / "residuals.png",
        )
    write_record(calibration, held_out, out_dir)
    write_summary(out_dir / CALIBRATION_FILE, summary)
    return summary


def _cell(value: float | None) -> str:
    return f"{value:>7.2f}" if value is not None else f"{'-':>7}"


def format_table(summary: CalibrationSummary) -> str:
    """The before/after table printed by ``posegen calibrate`` (mean absolute; RMS)."""
    lines = [
        "set                         contacts  model    z (mm)        roll (deg)    pitch (deg)",
        "                                              mean   rms    mean   rms    mean   rms",
    ]
    for key, table in summary.residuals.items():
        for model, errors in (("before", table.before), ("after", table.after)):
            cells = zip(errors.mean_abs.values(), errors.rms.values(), strict=True)
            lines.append(
                f"{key:<28}{table.contacts:>6}  {model:<7}" + "".join(f"{_cell(m)}{_cell(r)}" for m, r in cells)
            )
    return "\n".join(lines)
