"""Stage 2: the optimal choice of postures from a pool.

The design problem (one information matrix per posture, in the base parameters of the
calibration model), continuous D-optimal weights with their certificate (Frank-Wolfe),
exact k-posture designs (greedy, Fedorov exchange, DETMAX), IROC, and the selection
file (:class:`Selection`, :func:`read_selection`, :func:`write_selection`) with its plots.

Internal: scripts use the public API at ``posegen.`` (stable, documented with examples); the
names here are its plumbing and may change between versions.
"""

from posegen.io import (  # the selection file lives with the other artefacts' readers
    Certificate,
    ChosenPosture,
    DesignFigures,
    DetmaxFigures,
    Figures,
    FollowUpFigures,
    IrocFigures,
    Selection,
    SelectionMethod,
    SessionFigures,
    chosen_from_pool,
    read_selection,
    selection_from_dict,
    write_selection,
)
from posegen.model import Design, build_design
from posegen.select.figures import design_selection, plot_detmax, plot_o1
from posegen.select.followup import FollowUp, follow_up, read_calibration_model
from posegen.select.optimal_weights import OptimalWeights, d_optimal_weights
from posegen.select.selection import Iroc, detmax_runs, iroc, select_k, weight_of
from posegen.select.subset_selection import Subset, detmax, exchange, greedy, subset_of
from posegen.select.workflow import SelectionSettings, follow_up_pool_file, select_pool_file

__all__ = [
    "Certificate",
    "ChosenPosture",
    "Design",
    "DesignFigures",
    "DetmaxFigures",
    "Figures",
    "FollowUp",
    "FollowUpFigures",
    "Iroc",
    "IrocFigures",
    "OptimalWeights",
    "Selection",
    "SelectionMethod",
    "SelectionSettings",
    "SessionFigures",
    "Subset",
    "build_design",
    "chosen_from_pool",
    "d_optimal_weights",
    "design_selection",
    "detmax",
    "detmax_runs",
    "exchange",
    "follow_up",
    "follow_up_pool_file",
    "greedy",
    "iroc",
    "plot_detmax",
    "plot_o1",
    "read_calibration_model",
    "read_selection",
    "select_k",
    "select_pool_file",
    "selection_from_dict",
    "subset_of",
    "weight_of",
    "write_selection",
]
