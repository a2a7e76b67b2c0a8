"""The calibration folder's plots: laid out once, drawn once when written."""

import io

import numpy as np

from posegen.calibrate.plots import plot_residuals


def test_a_plot_is_drawn_once_when_written(figure_draws):
    """tight_layout leaves a layout engine behind, and savefig then draws a figure twice: the plots clear it."""
    residuals = np.random.default_rng(0).normal(0.0, 1e-3, (5, 3))  # (n, 3) m, rad, rad
    buffer = io.BytesIO()
    plot_residuals(residuals, residuals / 2, "residuals", buffer)
    assert len(figure_draws) == 1
    assert buffer.getvalue().startswith(b"\x89PNG")
