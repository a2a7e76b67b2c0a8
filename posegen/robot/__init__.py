"""The robot standing at the table: what every stage shares about it.

Typed config, the robot description and scene (model, stance, contact frames, table),
geometry, collisions (coal), the placo projection onto balanced contact, feasibility
measured independently of any solver, the stance space a planner moves in, contact
postures, and the files that carry postures between stages (pool, selection; routes are
in :mod:`posegen.io`).

Internal: scripts use the public API at ``posegen.`` (stable, documented with examples); the
names here are its plumbing and may change between versions.
"""

from posegen.robot.additions import (  # for the draft (robot init)
    Box,
    Capsule,
    CollisionConfig,
    DisabledPair,
    FrameConfig,
    Shape,
    VisualHull,
)
from posegen.robot.balance import (
    Balance,
    FloorWrenches,
    centre_of_pressure,
    centres_of_pressure,
    pressed_zmp_margin,
    stretch_for_margin,
    zmp_margins,
)
from posegen.robot.calibration_config import (
    MAX_FOLD_SEEDS,
    PRIOR_SCALE_RANGE,
    CalibrationConfig,
    CandidateConfig,
    PriorConfig,
    parse_candidate,
)
from posegen.robot.chain_config import ChainConfig
from posegen.robot.collision import TABLE, Collision, CollisionChecker, Proximity, Witness
from posegen.robot.collision_geometry import (
    add_self_pairs,  # for the draft (robot init)
    carrying_links,  # for physics: the links a contact exempts, as the collision check has them
    link_of,
    robot_geometry,
)
from posegen.robot.collision_matrix import PairSurvey, survey_pairs, survey_scene_pairs  # for the draft (robot init)
from posegen.robot.config import (
    PACKAGE_URI,  # for the draft (robot init)
    Config,
    MarginConfig,
    RecordingConfig,
    RobotSource,
    RouteConfig,
    SamplingConfig,
    StanceConfig,
    TableConfig,
    load_config,
    parse_config,
)
from posegen.robot.config_sections import leaves_no_room
from posegen.robot.contact_kinds import (
    DEFAULT_KIND,
    FLUSH,
    POINT,
    ContactKind,
    contact_placement,
    kind_named,
    registered_kinds,
)
from posegen.robot.coverage import (
    COVER_TOL_M,
    BareLink,  # for the draft (robot init)
    GeometryCoverage,
    bare_links,  # for the draft
    geometry_coverage,
    has_extent,  # for the draft
    left_out_m,  # for the draft
    link_masses,  # for the draft
)
from posegen.robot.description import (  # for the draft (robot init)
    RobotFiles,
    kinematic_urdf,
    package_uri,
    resolve_path,
    resolve_source,
    with_declared_frames,
)
from posegen.robot.feasibility import (
    SOLE_ANGLE_TOL_RAD,
    SOLE_POSITION_TOL_M,
    Assessment,
    Invariant,
    assess,
    contact_in_table,
)
from posegen.robot.geometry import (
    FloatArray,
    Indices,
    convex_hull_clockwise,
    cross,
    flatten_on_floor,
    polygon_margin,
    tilt_angles,
    yaw_rotation,
)
from posegen.robot.motion_torques import MotionTorques, PointLoad, allowed_ratios, effort_ratios_at, torque_stretch
from posegen.robot.projection import Projection, Projector
from posegen.robot.scene import Scene, Spot, scene_for, scene_for_postures
from posegen.robot.scene_parts import read_srdf_states
from posegen.robot.separation import Separation, SeparationRows
from posegen.robot.sole_split import COP_MARGIN_M, least_size_map, least_size_share, split_wrench
from posegen.robot.stance_space import StanceSpace
from posegen.robot.statics import (
    MOMENT_ARM_M,
    LinearTorques,
    Statics,
    TorquePair,
    effort_ratios,
    gravity_torques,
    holding_torques,
    linear_torques,
    worst_effort_ratio,
)
from posegen.robot.transforms import (
    offset_derivatives,
    offset_matrix,
    placement_derivatives,
    placement_matrix,
    rpy_derivatives,
    rpy_matrix,
    tilt_measurement,
    tilt_measurement_jacobian,
    translation_matrix,
)
from posegen.robot.validation import check_for_planning, check_reference_limits
from posegen.robot.verification import (
    EXAMPLES,
    JointEffort,
    Verification,
    Worst,
    WorstSoFar,
    summarize,
    worst_case,
)

__all__ = [
    "COP_MARGIN_M",
    "COVER_TOL_M",
    "DEFAULT_KIND",
    "EXAMPLES",
    "FLUSH",
    "MAX_FOLD_SEEDS",
    "MOMENT_ARM_M",
    "PACKAGE_URI",
    "POINT",
    "PRIOR_SCALE_RANGE",
    "SOLE_ANGLE_TOL_RAD",
    "SOLE_POSITION_TOL_M",
    "TABLE",
    "Assessment",
    "Balance",
    "BareLink",
    "Box",
    "CalibrationConfig",
    "CandidateConfig",
    "Capsule",
    "ChainConfig",
    "Collision",
    "CollisionChecker",
    "CollisionConfig",
    "Config",
    "ContactKind",
    "DisabledPair",
    "FloatArray",
    "FloorWrenches",
    "FrameConfig",
    "GeometryCoverage",
    "Indices",
    "Invariant",
    "JointEffort",
    "LinearTorques",
    "MarginConfig",
    "MotionTorques",
    "PairSurvey",
    "PointLoad",
    "PriorConfig",
    "Projection",
    "Projector",
    "Proximity",
    "RecordingConfig",
    "RobotFiles",
    "RobotSource",
    "RouteConfig",
    "SamplingConfig",
    "Scene",
    "Separation",
    "SeparationRows",
    "Shape",
    "Spot",
    "StanceConfig",
    "StanceSpace",
    "Statics",
    "TableConfig",
    "TorquePair",
    "Verification",
    "VisualHull",
    "Witness",
    "Worst",
    "WorstSoFar",
    "add_self_pairs",
    "allowed_ratios",
    "assess",
    "bare_links",
    "carrying_links",
    "centre_of_pressure",
    "centres_of_pressure",
    "check_for_planning",
    "check_reference_limits",
    "contact_in_table",
    "contact_placement",
    "convex_hull_clockwise",
    "cross",
    "effort_ratios",
    "effort_ratios_at",
    "flatten_on_floor",
    "geometry_coverage",
    "gravity_torques",
    "has_extent",
    "holding_torques",
    "kind_named",
    "kinematic_urdf",
    "least_size_map",
    "least_size_share",
    "leaves_no_room",
    "left_out_m",
    "linear_torques",
    "link_masses",
    "link_of",
    "load_config",
    "offset_derivatives",
    "offset_matrix",
    "package_uri",
    "parse_candidate",
    "parse_config",
    "placement_derivatives",
    "placement_matrix",
    "polygon_margin",
    "pressed_zmp_margin",
    "read_srdf_states",
    "registered_kinds",
    "resolve_path",
    "resolve_source",
    "robot_geometry",
    "rpy_derivatives",
    "rpy_matrix",
    "scene_for",
    "scene_for_postures",
    "split_wrench",
    "stretch_for_margin",
    "summarize",
    "survey_pairs",
    "survey_scene_pairs",
    "tilt_angles",
    "tilt_measurement",
    "tilt_measurement_jacobian",
    "torque_stretch",
    "translation_matrix",
    "with_declared_frames",
    "worst_case",
    "worst_effort_ratio",
    "yaw_rotation",
    "zmp_margins",
]
