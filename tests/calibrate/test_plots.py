"""The calibration folder's plots: laid out once, drawn once when written."""

import io
import warnings

import numpy as np

from posegen.calibrate.plots import plot_cross_validation, plot_residuals


def test_a_plot_is_drawn_once_when_written(figure_draws):
    """tight_layout leaves a layout engine behind, and savefig then draws a figure twice: the plots clear it."""
    residuals = np.random.default_rng(0).normal(0.0, 1e-3, (5, 3))  # (n, 3) m, rad, rad
    buffer = io.BytesIO()
    plot_residuals(residuals, residuals / 2, "residuals", buffer)
    assert len(figure_draws) == 1
    assert buffer.getvalue().startswith(b"\x89PNG")


def test_cross_validation_scores_that_a_log_axis_cannot_show_are_drawn_without_a_warning():
    """Scores all zero or unscored (inf) leave no positive value: matplotlib warned; the axis is then linear."""
    for score in (0.0, float("inf")):
        curves = {"offsets": [{"prior_scale": s, "score": score, "se": 0.0} for s in (1.0, 10.0)]}
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            plot_cross_validation(curves, ("offsets", 1.0), io.BytesIO())
