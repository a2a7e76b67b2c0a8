"""Stage 4: identification from recorded contacts, and its rehearsal on a simulated robot.

Measurements (posegen YAML and recorded CSV), maximum a posteriori estimation under a
physical prior per parameter kind, grouped cross-validation folds, the choice of the
model by repeated CV and the one-standard-error rule, robust screening of bad rows,
the whole calibration (before/after, held-out protocols), simulated contacts of a
perturbed robot, the calibrated URDF, the report (``calibration.yaml`` as a
:class:`CalibrationSummary`) and the folder read back (:func:`read_calibration`).

Internal: scripts use the public API at ``posegen.`` (stable, documented with examples); the
names here are its plumbing and may change between versions.
"""

from typing import TYPE_CHECKING, Any

from posegen.calibrate.calibration import Calibration, Settings, calibrate, held_out_residuals, held_out_x
from posegen.calibrate.calibration_file import write_calibration
from posegen.calibrate.compliance import Compliance, ComplianceGroup, compensate, read_compliance, uncompensate
from posegen.calibrate.deliverables import Deliverable, DeliverableKind, Deliverables
from posegen.calibrate.estimation import Estimate, Noise, estimate, fit, levenberg_marquardt
from posegen.calibrate.file_judge import JUDGED_AS, Judged, judge
from posegen.calibrate.folds import Fold, repeated_folds, spot_of
from posegen.calibrate.model_selection import ModelSelection, ScaleSearch, select_model
from posegen.calibrate.offsets import JointOffset, apply_offsets, joint_offsets, read_offsets
from posegen.calibrate.record import (
    CALIBRATION_FILE,
    CALIBRATION_FORMAT,
    COMPONENTS,
    DISPLAY,
    CalibrationRecord,
    ContactResidual,
    ContactSet,
    Posterior,
    contact_residuals,
    posterior_of,
    read_calibration,
    write_record,
)
from posegen.calibrate.scoring import RULE, CvResult
from posegen.calibrate.screening import Flag
from posegen.calibrate.simulated_recording import hermite
from posegen.calibrate.simulation import Perturbation, floor_constants, perturbed_robot, simulate, true_parameters
from posegen.calibrate.stream_topics import check_stream_topics, wrench_topics
from posegen.calibrate.summary import (
    CalibrationSummary,
    ChosenModel,
    Components,
    CvFigures,
    DeliverableSummary,
    ErrorFigures,
    FileFigures,
    LeftOutRow,
    SetFigures,
    read_summary,
    summary_from_dict,
    write_summary,
)
from posegen.calibrate.summary_text import file_lines, format_table, load_line, model_line
from posegen.calibrate.urdf_export import calibrated_config, calibrated_robot, calibrated_urdf, check_exportable
from posegen.calibrate.workflow import (
    Calibrated,
    Simulated,
    calibrate_files,
    check_compliance,
    perturbation_of,
    read_contacts,
    simulate_postures_file,
    truth_of,
    truth_record,
)

if TYPE_CHECKING:
    from posegen.calibrate.bag_workflow import (
        TRUTH_FILE,
        Measured,
        SimulatedBag,
        measure_bag,
        simulate_route_bag,
    )

_BAG_NAMES = (
    "TRUTH_FILE",
    "Measured",
    "SimulatedBag",
    "measure_bag",
    "simulate_route_bag",
)


def __getattr__(name: str) -> Any:
    """The rosbag workflow's names, imported when first used (``calibrate`` needs none of its readers)."""
    if name in _BAG_NAMES:
        from posegen.calibrate import bag_workflow

        return getattr(bag_workflow, name)
    raise AttributeError(f"module 'posegen.calibrate' has no attribute {name!r}")


__all__ = [
    "CALIBRATION_FILE",
    "CALIBRATION_FORMAT",
    "COMPONENTS",
    "DISPLAY",
    "JUDGED_AS",
    "RULE",
    "TRUTH_FILE",
    "Calibrated",
    "Calibration",
    "CalibrationRecord",
    "CalibrationSummary",
    "ChosenModel",
    "Compliance",
    "ComplianceGroup",
    "Components",
    "ContactResidual",
    "ContactSet",
    "CvFigures",
    "CvResult",
    "Deliverable",
    "DeliverableKind",
    "DeliverableSummary",
    "Deliverables",
    "ErrorFigures",
    "Estimate",
    "FileFigures",
    "Flag",
    "Fold",
    "JointOffset",
    "Judged",
    "LeftOutRow",
    "Measured",
    "ModelSelection",
    "Noise",
    "Perturbation",
    "Posterior",
    "ScaleSearch",
    "SetFigures",
    "Settings",
    "Simulated",
    "SimulatedBag",
    "apply_offsets",
    "calibrate",
    "calibrate_files",
    "calibrated_config",
    "calibrated_robot",
    "calibrated_urdf",
    "check_compliance",
    "check_exportable",
    "check_stream_topics",
    "compensate",
    "contact_residuals",
    "estimate",
    "file_lines",
    "fit",
    "floor_constants",
    "format_table",
    "held_out_residuals",
    "held_out_x",
    "hermite",
    "joint_offsets",
    "judge",
    "levenberg_marquardt",
    "load_line",
    "measure_bag",
    "model_line",
    "perturbation_of",
    "perturbed_robot",
    "posterior_of",
    "read_calibration",
    "read_compliance",
    "read_contacts",
    "read_offsets",
    "read_summary",
    "repeated_folds",
    "select_model",
    "simulate",
    "simulate_postures_file",
    "simulate_route_bag",
    "spot_of",
    "summary_from_dict",
    "true_parameters",
    "truth_of",
    "truth_record",
    "uncompensate",
    "wrench_topics",
    "write_calibration",
    "write_record",
    "write_summary",
]
