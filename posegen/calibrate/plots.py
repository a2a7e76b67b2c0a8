"""The calibration's plots: identified deviations, held-out residuals, cross-validation curves."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from posegen.calibrate.record import DISPLAY
from posegen.io import atomic_path
from posegen.robot import FloatArray


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_parameters(rows: list[dict[str, Any]], path: Path) -> None:
    """Bar chart of the fitted deviations, lengths (mm) and angles (deg), with posterior std."""
    plt = _pyplot()
    fig, axes = plt.subplots(2, 1, figsize=(14, 7))
    for ax, unit, label in ((axes[0], "mm", "length deviation (mm)"), (axes[1], "deg", "angle deviation (deg)")):
        sel = [r for r in rows if r["unit"] == unit]
        x = np.arange(len(sel))
        ax.bar(x, [r["deviation"] for r in sel], yerr=[r["std"] for r in sel], color="tab:blue")
        ax.set_xticks(x, [r["name"].replace("_joint", "") for r in sel], rotation=90, fontsize=6)
        ax.set_ylabel(label)
        ax.axhline(0, color="black", lw=0.5)
        ax.grid(axis="y", alpha=0.3)
    axes[0].set_title("Fitted deviations from the URDF (posterior std)")
    fig.tight_layout()
    with atomic_path(path) as tmp:  # a killed run leaves the old plot or the new one
        fig.savefig(tmp, dpi=110)
    plt.close(fig)


def plot_residuals(
    before: FloatArray,
    after: FloatArray,
    title: str,
    path: Path,
    labels: tuple[str, str] = ("nominal URDF", "calibrated.urdf"),
) -> None:
    """Per-contact residuals (n, 3) of two models (m, rad; NaN: not measured), for height, roll and pitch."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    x = np.arange(len(before))
    for k, (ax, name) in enumerate(zip(axes, ("height (mm)", "roll (deg)", "pitch (deg)"), strict=True)):
        ax.bar(x - 0.2, before[:, k] * DISPLAY[k], width=0.4, label=labels[0], color="tab:gray")
        ax.bar(x + 0.2, after[:, k] * DISPLAY[k], width=0.4, label=labels[1], color="tab:green")
        ax.axhline(0, color="black", lw=0.5)
        ax.set_xlabel("contact")
        ax.set_title(name)
        ax.grid(axis="y", alpha=0.3)
    axes[0].legend()
    fig.suptitle(title)
    fig.tight_layout()
    with atomic_path(path) as tmp:  # a killed run leaves the old plot or the new one
        fig.savefig(tmp, dpi=110)
    plt.close(fig)


def plot_cross_validation(curves: dict[str, list[dict[str, float]]], chosen: tuple[str, float], path: Path) -> None:
    """CV score (with one standard error) of each candidate over the prior scale; the chosen pair marked."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(9, 5))
    for name, points in curves.items():
        scales = [p["prior_scale"] for p in points]
        ax.errorbar(scales, [p["score"] for p in points], yerr=[p["se"] for p in points], label=name, capsize=2)
    chosen_point = next(p for p in curves[chosen[0]] if p["prior_scale"] == chosen[1])
    ax.plot([chosen[1]], [chosen_point["score"]], "k*", markersize=14, label="chosen (one-SE rule)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("prior scale (x the kind sigmas)")
    ax.set_ylabel("CV score: mean of (z/1 mm)^2 + (roll/0.1 deg)^2 + (pitch/0.1 deg)^2")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    fig.tight_layout()
    with atomic_path(path) as tmp:  # a killed run leaves the old plot or the new one
        fig.savefig(tmp, dpi=110)
    plt.close(fig)
