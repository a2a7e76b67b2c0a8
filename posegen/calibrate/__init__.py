"""Stage 4: identification from recorded contacts, and its rehearsal on a simulated robot.

Measurements (posegen YAML and recorded CSV), Levenberg-Marquardt identification of
the base parameters, the whole calibration (prior and noise by cross-validation,
outliers, before/after, held-out protocols), simulated contacts of a perturbed robot,
the calibrated URDF, the report and the folder read back (:func:`read_calibration`).
"""

from posegen.calibrate.bag_workflow import Measured, SimulatedSession, measure_bag, simulate_route_bag
from posegen.calibrate.calibration import (
    Calibration,
    CvPoint,
    Settings,
    calibrate,
    cross_validate,
    held_out_residuals,
    held_out_theta,
    outlier_threshold,
)
from posegen.calibrate.identification import Fit, identify, levenberg_marquardt, refit_planes
from posegen.calibrate.measurements import (
    Recording,
    measurements_to_dict,
    read_csv,
    read_measurements,
    write_measurements,
)
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
from posegen.calibrate.report import format_table, residual_stats, write_calibration
from posegen.calibrate.simulation import Perturbation, simulate, true_parameters
from posegen.calibrate.urdf_export import calibrated_urdf
from posegen.calibrate.workflow import Calibrated, Simulated, calibrate_files, read_contacts, simulate_plan_file

__all__ = [
    "CALIBRATION_FILE",
    "CALIBRATION_FORMAT",
    "COMPONENTS",
    "DISPLAY",
    "Calibrated",
    "Calibration",
    "CalibrationRecord",
    "ContactResidual",
    "ContactSet",
    "CvPoint",
    "Fit",
    "Measured",
    "Perturbation",
    "Posterior",
    "Recording",
    "Settings",
    "Simulated",
    "SimulatedSession",
    "calibrate",
    "calibrate_files",
    "calibrated_urdf",
    "contact_residuals",
    "cross_validate",
    "format_table",
    "held_out_residuals",
    "held_out_theta",
    "identify",
    "levenberg_marquardt",
    "measure_bag",
    "measurements_to_dict",
    "outlier_threshold",
    "posterior_of",
    "read_calibration",
    "read_contacts",
    "read_csv",
    "read_measurements",
    "refit_planes",
    "residual_stats",
    "simulate",
    "simulate_plan_file",
    "simulate_route_bag",
    "true_parameters",
    "write_calibration",
    "write_measurements",
    "write_record",
]
