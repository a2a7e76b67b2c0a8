"""The report's figures: laid out once, drawn once when saved."""

import base64

import matplotlib.pyplot as plt

from posegen.view.report_figures import png_data_uri


def test_a_figure_is_laid_out_then_drawn_once(figure_draws):
    """tight_layout leaves a layout engine behind, and savefig then draws a figure twice: png_data_uri clears it."""
    fig, ax = plt.subplots(figsize=(4, 3))
    ax.plot([0, 1], [0, 1])
    ax.set_ylabel("a label that tight_layout makes room for")
    uri = png_data_uri(fig)
    assert len(figure_draws) == 1
    assert base64.b64decode(uri.removeprefix("data:image/png;base64,")).startswith(b"\x89PNG")
    assert fig.subplotpars.left > plt.rcParams["figure.subplot.left"]  # laid out: room made for the label
