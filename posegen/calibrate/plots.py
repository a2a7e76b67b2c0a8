"""The calibration's plots: identified deviations, held-out residuals, cross-validation curves.

Each plot is a pure function of its data (a :class:`Plot`), drawn to PNG bytes: the
command draws them on its idle worker processes while it writes the report
(:func:`drawing`), the same bytes as drawn in its own process.
"""

from __future__ import annotations

import io
import threading
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from posegen.calibrate.record import DISPLAY
from posegen.io import atomic_path, write_atomic
from posegen.parallel import Backend, Job, job_name, no_state
from posegen.robot import FloatArray

DPI = 110


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_parameters(rows: list[dict[str, Any]], path: Path | io.BytesIO) -> None:
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
    _save(plt, fig, path)


def plot_residuals(
    before: FloatArray,
    after: FloatArray,
    title: str,
    path: Path | io.BytesIO,
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
    _save(plt, fig, path)


def plot_cross_validation(
    curves: dict[str, list[dict[str, float]]], chosen: tuple[str, float], path: Path | io.BytesIO
) -> None:
    """CV score (with one standard error) of each candidate over the prior scale; the chosen pair marked."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(9, 5))
    for name, points in curves.items():
        scales = [p["prior_scale"] for p in points]
        ax.errorbar(scales, [p["score"] for p in points], yerr=[p["se"] for p in points], label=name, capsize=2)
    chosen_point = next(p for p in curves[chosen[0]] if p["prior_scale"] == chosen[1])
    ax.plot([chosen[1]], [chosen_point["score"]], "k*", markersize=14, label="chosen (one-SE rule)")
    ax.set_xscale("log")
    scores = np.array([p["score"] for points in curves.values() for p in points])
    if np.any(np.isfinite(scores) & (scores > 0)):  # all zero or unscored (a degenerate design): a linear axis
        ax.set_yscale("log")
    ax.set_xlabel("prior scale (x the kind sigmas)")
    ax.set_ylabel("CV score: mean of (z/1 mm)^2 + (roll/0.1 deg)^2 + (pitch/0.1 deg)^2")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    _save(plt, fig, path)


def _save(plt: Any, fig: Any, path: Path | io.BytesIO) -> None:
    """Lay ``fig`` out, write it as PNG (a file atomically: a killed run leaves the old one or the new), close it."""
    fig.tight_layout()
    fig.set_layout_engine(None)  # laid out once: with tight_layout's engine left behind, savefig would draw twice
    if isinstance(path, io.BytesIO):
        fig.savefig(path, format="png", dpi=DPI)
    else:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=DPI)
    plt.close(fig)


@dataclass(frozen=True)
class Plot:
    """One plot of a calibration folder: its drawing function's name, arguments (all but the path) and file."""

    kind: str  # "parameters", "residuals" or "cross_validation"
    arguments: tuple[Any, ...]
    path: Path


DRAW: dict[str, Callable[..., None]] = {
    "parameters": plot_parameters,
    "residuals": plot_residuals,
    "cross_validation": plot_cross_validation,
}


def png_bytes(plot: Plot) -> bytes:
    """The plot drawn, as the bytes of its PNG file."""
    buffer = io.BytesIO()
    DRAW[plot.kind](*plot.arguments, path=buffer)
    return buffer.getvalue()


def _draw(state: None, plot: Plot) -> bytes:
    del state
    return png_bytes(plot)


def draw_all(plots: Sequence[Plot], backend: Backend | None = None) -> None:
    """Draw ``plots`` into their files: over ``backend``'s workers, or here (None, or one slot)."""
    if backend is None or backend.slots < 2 or len(plots) < 2:
        for plot in plots:
            DRAW[plot.kind](*plot.arguments, path=plot.path)
        return
    job: Job[None, Plot, bytes] = Job(job_name("calibrate-plots"), no_state, _draw)
    for plot, data in zip(plots, backend.map(job, plots, len(plots)), strict=True):
        write_atomic(plot.path, data)  # written here: a worker may not see this folder


@contextmanager
def drawing(plots: Sequence[Plot], backend: Backend | None = None) -> Iterator[None]:
    """Draw ``plots`` on ``backend``'s workers while the block runs; every file is written when it ends.

    With no backend, or one slot, they are drawn here first. An error of either is raised
    (the block's first).
    """
    if backend is None or backend.slots < 2 or len(plots) < 2:
        draw_all(plots)
        yield
        return
    failed: list[BaseException] = []

    def work() -> None:
        try:
            draw_all(plots, backend)
        except BaseException as exc:  # raised in the caller's thread below
            failed.append(exc)

    thread = threading.Thread(target=work, name="posegen-calibrate-plots", daemon=True)
    thread.start()
    try:
        yield
    finally:
        thread.join()
    if failed:
        raise failed[0]
