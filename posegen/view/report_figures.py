"""The calibration report's figures, as PNG images inlined in the page (base64).

Residuals per contact (training and held-out) under the nominal URDF and calibrated.urdf,
each as a stack loading it sees them, their distribution,
the singular values of the base regressor, and the posterior correlation matrix.

:func:`figure_uris` draws all four, on a backend's workers when it has more than one
(each figure in a worker while the page's other parts are made here: the same PNG bytes).
"""

from __future__ import annotations

import base64
import enum
import io
from collections.abc import Sequence

import numpy as np

from posegen.calibrate import DISPLAY, ContactResidual, ContactSet, Posterior
from posegen.parallel import Backend, Job, job_name, no_state
from posegen.robot import FloatArray

COMPONENTS = ("height (mm)", "roll (deg)", "pitch (deg)")
SET_COLOURS = {ContactSet.TRAINING: "tab:green", ContactSet.OUTLIER: "tab:red", ContactSet.HELD_OUT: "tab:purple"}


def _pyplot():  # type: ignore[no-untyped-def]
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def png_data_uri(figure: object) -> str:
    """A matplotlib figure, laid out, as a ``data:image/png`` URI (the figure is closed)."""
    plt = _pyplot()
    figure.tight_layout()  # type: ignore[attr-defined]
    # laid out once: with the layout engine tight_layout leaves behind, savefig would draw the figure twice
    figure.set_layout_engine(None)  # type: ignore[attr-defined]
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=90)  # type: ignore[attr-defined]
    plt.close(figure)
    return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")


def residual_figure(contacts: Sequence[ContactResidual]) -> str:
    """Per-contact residuals: before (grey) and after (by set) on one scale, and after alone on its own."""
    plt = _pyplot()
    fig, axes = plt.subplots(3, 2, figsize=(11, 7.5), sharex=True, gridspec_kw={"width_ratios": (3, 2)})
    x = np.arange(len(contacts))
    before = np.array([c.before for c in contacts]).reshape(-1, 3) * DISPLAY
    after = np.array([c.after for c in contacts]).reshape(-1, 3) * DISPLAY
    colours = [SET_COLOURS[c.set] for c in contacts]
    for k in range(3):
        both, alone = axes[k]
        both.scatter(x, before[:, k], s=9, color="0.6", label="nominal URDF")
        both.scatter(x, after[:, k], s=9, color=colours, label="calibrated.urdf")
        alone.scatter(x, after[:, k], s=9, color=colours)
        both.set_ylabel(COMPONENTS[k])
        for ax in (both, alone):
            ax.axhline(0.0, color="black", lw=0.5)
            ax.grid(alpha=0.3)
            for contact_set in ContactSet:
                rows = [i for i, c in enumerate(contacts) if c.set == contact_set]
                if rows:
                    ax.axvspan(rows[0] - 0.5, rows[-1] + 0.5, color=SET_COLOURS[contact_set], alpha=0.06)
    axes[0][0].legend(loc="lower right", fontsize=8)
    axes[0][0].set_title("nominal URDF and calibrated.urdf (as a stack loading each sees it)")
    axes[0][1].set_title("calibrated.urdf (its own scale)")
    labels = ", ".join(f"{s.value.replace('_', '-')} ({SET_COLOURS[s].removeprefix('tab:')})" for s in ContactSet)
    for ax in axes[-1]:
        ax.set_xlabel("contact: " + labels if ax is axes[-1][0] else "contact")
    return png_data_uri(fig)


def distribution_figure(contacts: Sequence[ContactResidual]) -> str:
    """Histograms of |residual| under calibrated.urdf, training against held-out (NaN: not measured, not drawn)."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(11, 3))
    for k, ax in enumerate(axes):
        for contact_set in (ContactSet.TRAINING, ContactSet.HELD_OUT):
            values = [abs(c.after[k]) * DISPLAY[k] for c in contacts if c.set == contact_set]
            values = [v for v in values if np.isfinite(v)]  # not measured (NaN): not drawn
            if values:
                ax.hist(values, bins=20, alpha=0.6, color=SET_COLOURS[contact_set], label=contact_set.value)
        ax.set_xlabel("|" + COMPONENTS[k].replace(" (", "| (", 1))
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("contacts")
    axes[0].legend(fontsize=8)
    return png_data_uri(fig)


def singular_value_figure(posterior: Posterior) -> str:
    """Singular values of the noise-whitened base regressor (log scale)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(11, 3))
    values = posterior.singular_values
    ax.semilogy(np.arange(1, len(values) + 1), values, "o-", ms=3)
    ax.set_xlabel("singular value index")
    ax.set_ylabel("singular value (whitened)")
    ax.set_title(f"base regressor: condition number {posterior.condition:.3g}")
    ax.grid(alpha=0.3, which="both")
    return png_data_uri(fig)


def correlation_figure(posterior: Posterior) -> str:
    """The posterior correlation matrix of the base parameters."""
    plt = _pyplot()
    n = len(posterior.names)
    size = min(11.0, 4.0 + 0.06 * n)
    fig, ax = plt.subplots(figsize=(size, size * 0.85))
    image = ax.imshow(posterior.correlation, cmap="RdBu_r", vmin=-1.0, vmax=1.0)
    fig.colorbar(image, ax=ax, shrink=0.8, label="correlation")
    if n <= 60:
        ax.set_xticks(range(n), posterior.names, rotation=90, fontsize=5)
        ax.set_yticks(range(n), posterior.names, fontsize=5)
    ax.set_title("posterior correlation of the base parameters")
    return png_data_uri(fig)


class ReportFigure(enum.Enum):
    """The report's figures (the longest to draw first: the workers end together)."""

    CORRELATION = "correlation"
    RESIDUALS = "residuals"
    SINGULAR_VALUES = "singular values"
    DISTRIBUTION = "distribution"


def _draw(state: None, item: tuple[ReportFigure, Sequence[ContactResidual], Posterior]) -> str:
    """One figure's data URI, from the contacts' residuals or the posterior (whichever it shows)."""
    del state
    kind, contacts, posterior = item
    if kind == ReportFigure.RESIDUALS:
        return residual_figure(contacts)
    if kind == ReportFigure.DISTRIBUTION:
        return distribution_figure(contacts)
    if kind == ReportFigure.SINGULAR_VALUES:
        return singular_value_figure(posterior)
    return correlation_figure(posterior)


def figure_uris(
    contacts: Sequence[ContactResidual], posterior: Posterior, backend: Backend | None = None
) -> dict[ReportFigure, str]:
    """Every report figure as a ``data:image/png`` URI: on ``backend``'s workers (all at once), or here.

    Example:
        >>> uris = figure_uris(record.contacts, record.posterior)
        >>> uris[ReportFigure.RESIDUALS].startswith("data:image/png;base64,")
        True

    """
    items = [(kind, contacts, posterior) for kind in ReportFigure]
    if backend is None or backend.slots < 2:
        return {item[0]: _draw(None, item) for item in items}
    job: Job[None, tuple[ReportFigure, Sequence[ContactResidual], Posterior], str] = Job(
        job_name("report-figures"), no_state, _draw
    )
    return dict(zip(ReportFigure, backend.map(job, items, len(items)), strict=True))


def strongest_correlations(posterior: Posterior, count: int = 12) -> list[tuple[str, str, float]]:
    """The ``count`` most correlated pairs of base parameters, strongest first."""
    rho: FloatArray = posterior.correlation
    upper = np.triu_indices(len(rho), k=1)
    order = np.argsort(-np.abs(rho[upper]))[:count]
    return [(posterior.names[int(upper[0][i])], posterior.names[int(upper[1][i])], float(rho[upper][i])) for i in order]
