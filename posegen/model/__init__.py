"""The calibration model that selection and identification share.

Parametric sole-to-contact kinematics of each chain, the plane-constrained contact
model (flush and point contacts) with its analytic Jacobian, which rows each contact
kind measures, the parameters and their names, noise and prior
weights, initial plane estimates, the settle step of a force-controlled contact,
identifiability (base parameters by QR, structural base parameters, O1), and the
experiment design (one information matrix per candidate posture) that selection solves
and the route's repair consults.

Internal: scripts use the public API at ``posegen.`` (stable, documented with examples); the
names here are its plumbing and may change between versions.
"""

from posegen.model.calibration_model import CalibrationModel, Evaluation, Observations, body_parts, start_point
from posegen.model.contact_model import ContactModel, Contacts, planned_kinds
from posegen.model.contact_rows import masked, row_counts, row_mask
from posegen.model.design import RIDGE, SINGULAR, Design, build_design, information
from posegen.model.evaluations import Evaluations
from posegen.model.floor_model import FLOOR_FIELDS, SESSION_FIELDS, FloorModel
from posegen.model.identifiability import RANK_TOLERANCE, BaseParameters, base_parameters, observability_o1
from posegen.model.kinds import Direction, Kind, Part, kind_basis
from posegen.model.kinematics import ChainModel
from posegen.model.measurements import (
    LIMIT_TOLERANCE_RAD,
    MEASUREMENT_FORMAT,
    Measurements,
    existing_measurement_file,
    measurement_item,
    measurement_provenance,
    measurements_to_dict,
    read_csv,
    read_measurements,
    write_measurements,
)
from posegen.model.parameters import OFFSET_FIELDS, PLACEMENT_FIELDS, POINT_FIELDS, Group, Parameter, Unit
from posegen.model.planes import initial_planes, level_planes
from posegen.model.pool_size import POOL_FACTOR, PoolSize, minimum_postures, pool_size
from posegen.model.prior import (
    ROBOT_KINDS,
    Spec,
    candidate_spec,
    free_directions,
    kind_sigmas,
    prior_sigmas,
    spec_for_rows,
)
from posegen.model.settle import settle, settle_contacts
from posegen.model.structural import STRUCTURAL_POSTURES, base_at, level_postures, structural_base
from posegen.model.weights import (
    DEFAULT_FLOOR_NOISE,
    DEFAULT_NOISE,
    NOISE_FLOOR,
    UNIT_PRIOR_ANGLE_RAD,
    UNIT_PRIOR_LENGTH_M,
    Weights,
    prior_scale,
    weights_for,
)
from posegen.robot import offset_matrix, placement_derivatives, placement_matrix, rpy_matrix  # the model's transforms

__all__ = [
    "DEFAULT_FLOOR_NOISE",
    "DEFAULT_NOISE",
    "FLOOR_FIELDS",
    "LIMIT_TOLERANCE_RAD",
    "MEASUREMENT_FORMAT",
    "NOISE_FLOOR",
    "OFFSET_FIELDS",
    "PLACEMENT_FIELDS",
    "POINT_FIELDS",
    "POOL_FACTOR",
    "RANK_TOLERANCE",
    "RIDGE",
    "ROBOT_KINDS",
    "SESSION_FIELDS",
    "SINGULAR",
    "STRUCTURAL_POSTURES",
    "UNIT_PRIOR_ANGLE_RAD",
    "UNIT_PRIOR_LENGTH_M",
    "BaseParameters",
    "CalibrationModel",
    "ChainModel",
    "ContactModel",
    "Contacts",
    "Design",
    "Direction",
    "Evaluation",
    "Evaluations",
    "FloorModel",
    "Group",
    "Kind",
    "Measurements",
    "Observations",
    "Parameter",
    "Part",
    "PoolSize",
    "Spec",
    "Unit",
    "Weights",
    "base_at",
    "base_parameters",
    "body_parts",
    "build_design",
    "candidate_spec",
    "existing_measurement_file",
    "free_directions",
    "information",
    "initial_planes",
    "kind_basis",
    "kind_sigmas",
    "level_planes",
    "level_postures",
    "masked",
    "measurement_item",
    "measurement_provenance",
    "measurements_to_dict",
    "minimum_postures",
    "observability_o1",
    "offset_matrix",
    "placement_derivatives",
    "placement_matrix",
    "planned_kinds",
    "pool_size",
    "prior_scale",
    "prior_sigmas",
    "read_csv",
    "read_measurements",
    "row_counts",
    "row_mask",
    "rpy_matrix",
    "settle",
    "settle_contacts",
    "spec_for_rows",
    "start_point",
    "structural_base",
    "weights_for",
    "write_measurements",
]
