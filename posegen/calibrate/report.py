"""What a calibration run writes: report YAML, residual tables, plots, calibrated URDF.

Output folder::

    calibration.yaml     parameters, base parameters, weights, CV, outliers, residual tables, provenance
    residuals.csv        every contact's residuals before and after, and its joint angles
    posterior.npz        posterior covariance of the base parameters, conditioning of their regressor
    calibrated.urdf      same links and joints, calibrated origins
    calibrated.yaml      a scene config that uses calibrated.urdf
    parameters.png       identified deviations per placement (mm, deg)
    residuals.png        held-out residuals before/after (or training ones without held-out data)
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from posegen.calibrate.calibration import Calibration, held_out_residuals
from posegen.calibrate.record import CALIBRATION_FORMAT, COMPONENTS, DISPLAY, write_record
from posegen.calibrate.urdf_export import calibrated_urdf
from posegen.io import dump_yaml, write_atomic
from posegen.model import OFFSET_FIELDS, Contacts, Group, Parameter, Unit
from posegen.robot import FloatArray


def residual_stats(residuals: FloatArray) -> dict[str, dict[str, float]]:
    """RMS and mean absolute of (n, 3) residuals, in mm and deg."""
    shown = residuals * DISPLAY
    return {
        "mean_abs": {c: round(float(v), 4) for c, v in zip(COMPONENTS, np.mean(np.abs(shown), axis=0), strict=True)},
        "rms": {c: round(float(v), 4) for c, v in zip(COMPONENTS, np.sqrt(np.mean(shown**2, axis=0)), strict=True)},
    }


def residual_tables(calibration: Calibration, held_out: Contacts | None) -> dict[str, Any]:
    """Training and held-out residual statistics, before and after."""
    kept = list(calibration.kept)
    train_before = calibration.model.residuals(calibration.before.theta, calibration.train.subset(kept))
    train_after = calibration.model.residuals(calibration.after.theta, calibration.train.subset(kept))
    tables: dict[str, Any] = {
        "training": {
            "before": residual_stats(train_before),
            "after": residual_stats(train_after),
            "contacts": len(kept),
        }
    }
    if held_out is not None:
        for protocol, by_model in held_out_residuals(calibration, held_out).items():
            tables[f"held_out_{protocol}"] = {k: residual_stats(v) for k, v in by_model.items()}
            tables[f"held_out_{protocol}"]["contacts"] = len(held_out)
    return tables


def parameter_table(calibration: Calibration) -> list[dict[str, Any]]:
    """Every base parameter: nominal, identified, deviation and its posterior std (m/rad)."""
    model = calibration.model
    nominal = model.nominal()
    rows = []
    for i in calibration.base.columns:
        p = model.parameters[i]
        rows.append(
            {
                "name": p.name,
                "group": p.group.value,
                "unit": p.unit.value,
                "nominal": float(nominal[i]),
                "identified": float(calibration.after.theta[i]),
                "deviation": float(calibration.after.theta[i] - nominal[i]),
                "std": float(calibration.after.std[i]),
            }
        )
    return rows


def base_parameter_summary(calibration: Calibration) -> dict[str, Any]:
    """Counts of base parameters by group and by chain."""
    model = calibration.model
    params = [model.parameters[i] for i in calibration.base.columns]
    by_group = {g.value: sum(p.group == g for p in params) for g in Group}
    by_chain = {}
    for name, chain in model.chains.items():
        owners = set(chain.placement_names) | {chain.contact_frame}
        by_chain[name] = sum(p.owner in owners for p in params)
    return {
        "total": len(params),
        "parameters": model.size,
        "by_group": by_group,
        "robot_parameters_per_chain": by_chain,
        "note": "robot parameters shared by chains (torso) count in each chain; planes per session",
    }


def plot_parameters(calibration: Calibration, path: Path) -> None:
    """Bar chart of identified deviations per placement: lengths (mm) and angles (deg)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = [r for r in parameter_table(calibration) if r["group"] != Group.PLANE.value]
    fig, axes = plt.subplots(2, 1, figsize=(14, 7), sharex=False)
    for ax, unit, scale, label in (
        (axes[0], Unit.LENGTH.value, 1e3, "length deviation (mm)"),
        (axes[1], Unit.ANGLE.value, 180 / np.pi, "angle deviation (deg)"),
    ):
        sel = [r for r in rows if r["unit"] == unit]
        x = np.arange(len(sel))
        ax.bar(x, [r["deviation"] * scale for r in sel], yerr=[r["std"] * scale for r in sel], color="tab:blue")
        ax.set_xticks(x, [r["name"].replace("_joint", "") for r in sel], rotation=90, fontsize=6)
        ax.set_ylabel(label)
        ax.axhline(0, color="black", lw=0.5)
        ax.grid(axis="y", alpha=0.3)
    axes[0].set_title("Identified base parameters (deviation from the URDF, with posterior std)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_residuals(before: FloatArray, after: FloatArray, title: str, path: Path) -> None:
    """Per-contact residuals before and after, for height, roll and pitch."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    x = np.arange(len(before))
    for k, (ax, name) in enumerate(zip(axes, ("height (mm)", "roll (deg)", "pitch (deg)"), strict=True)):
        ax.bar(x - 0.2, before[:, k] * DISPLAY[k], width=0.4, label="before", color="tab:gray")
        ax.bar(x + 0.2, after[:, k] * DISPLAY[k], width=0.4, label="after", color="tab:green")
        ax.axhline(0, color="black", lw=0.5)
        ax.set_xlabel("contact")
        ax.set_title(name)
        ax.grid(axis="y", alpha=0.3)
    axes[0].legend()
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_calibration(
    calibration: Calibration,
    held_out: Contacts | None,
    out_dir: Path,
    seed: int | None,
    rejected_rows: Sequence[str] = (),
) -> dict[str, Any]:
    """Write every output of a calibration into ``out_dir`` and return the report.

    Args:
        calibration: The calibration.
        held_out: Held-out contacts, if any.
        out_dir: Output folder (created).
        seed: Seed recorded in the provenance.
        rejected_rows: Input rows left out as unusable, one message each.

    """
    scene = calibration.model.scene
    out_dir.mkdir(parents=True, exist_ok=True)
    tables = residual_tables(calibration, held_out)
    model = calibration.model
    report = {
        "format": CALIBRATION_FORMAT,
        "format_version": 1,
        "provenance": scene.provenance(seed),
        "chains": sorted(model.chains),
        "sessions": list(model.sessions),
        "weights": {
            "noise": dict(
                zip(COMPONENTS, (np.array(calibration.weights.noise) * DISPLAY).round(4).tolist(), strict=True)
            ),
            "prior_length_mm": calibration.weights.prior_length_m * 1e3,
            "prior_angle_deg": float(np.rad2deg(calibration.weights.prior_angle_rad)),
        },
        "cross_validation": [
            {
                "prior_scale": p.kappa,
                "score": round(p.score, 4),
                "mean_abs": dict(zip(COMPONENTS, (np.array(p.mean_abs) * DISPLAY).round(3).tolist(), strict=True)),
            }
            for p in calibration.cv
        ],
        "rejected_rows": list(rejected_rows),
        "outliers": [
            {"contact": calibration.train.labels[i], "normalised_cv_residual": round(s, 2)}
            for i, s in zip(calibration.outliers, calibration.outlier_scores, strict=True)
        ],
        "base_parameters": base_parameter_summary(calibration),
        "residuals": tables,
        "planes": {
            s: {f: float(calibration.after.theta[model.column(Parameter.plane(s, f))]) for f in OFFSET_FIELDS}
            for s in model.sessions
        },
        "parameters": parameter_table(calibration),
    }
    urdf = calibrated_urdf(scene.files.urdf.read_text(), model, calibration.after.theta)
    write_atomic(out_dir / "calibrated.urdf", urdf)
    config = scene.config.to_dict()
    config["robot"]["source"] = {
        "urdf": str((out_dir / "calibrated.urdf").resolve()),
        "srdf": str(scene.files.srdf),
        "package_dirs": list(scene.files.package_dirs),
    }
    write_atomic(out_dir / "calibrated.yaml", dump_yaml(config))
    plot_parameters(calibration, out_dir / "parameters.png")
    if held_out is not None:
        res = held_out_residuals(calibration, held_out)["training_plane"]
        plot_residuals(
            res["before"], res["after"], "Held-out residuals (plane from training)", out_dir / "residuals.png"
        )
    else:
        sub = calibration.train.subset(list(calibration.kept))
        plot_residuals(
            model.residuals(calibration.before.theta, sub),
            model.residuals(calibration.after.theta, sub),
            "Training residuals",
            out_dir / "residuals.png",
        )
    write_record(calibration, held_out, out_dir)
    write_atomic(out_dir / "calibration.yaml", dump_yaml(report))
    return report


def format_table(report: dict[str, Any]) -> str:
    """The before/after table printed by ``posegen calibrate`` (mean absolute; RMS)."""
    lines = [
        "set                         contacts  model    z (mm)        roll (deg)    pitch (deg)",
        "                                              mean   rms    mean   rms    mean   rms",
    ]
    for key, table in report["residuals"].items():
        for model in ("before", "after"):
            m, r = table[model]["mean_abs"], table[model]["rms"]
            lines.append(
                f"{key:<28}{table['contacts']:>6}  {model:<7}"
                + "".join(f"{m[c]:>7.2f}{r[c]:>7.2f}" for c in COMPONENTS)
            )
    return "\n".join(lines)
