"""The robot standing at the table: what every stage shares about it.

Typed config, the robot description and scene (model, stance, contact frames, table),
geometry, collisions (coal), the placo projection onto balanced contact, feasibility
measured independently of any solver, the stance space a planner moves in, contact
postures, and the files that carry postures and trajectories between stages (pool,
selection, route).
"""

from posegen.robot.collision import TABLE, CollisionChecker, Proximity
from posegen.robot.config import (
    ChainConfig,
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
from posegen.robot.description import RobotFiles, contact_placement, kinematic_urdf
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
    flatten_on_floor,
    polygon_margin,
    tilt_angles,
    yaw_rotation,
)
from posegen.robot.postures import (
    POOL_FORMAT,
    POOL_VERSION,
    SELECTION_FORMAT,
    Pool,
    Posture,
    load_plan,
    load_pool,
    plan_entries,
    pool_from_dict,
    posture_from_dict,
    write_pool,
)
from posegen.robot.projection import Projection, Projector
from posegen.robot.scene import Scene, Spot, scene_for
from posegen.robot.stance_space import StanceSpace
from posegen.robot.trajectory import ROUTE_FORMAT, ROUTE_VERSION, SegmentType, is_route_file, read_route, route_arrays
from posegen.robot.verification import Verification, Worst, WorstSoFar, summarize

__all__ = [
    "POOL_FORMAT",
    "POOL_VERSION",
    "ROUTE_FORMAT",
    "ROUTE_VERSION",
    "SELECTION_FORMAT",
    "SOLE_ANGLE_TOL_RAD",
    "SOLE_POSITION_TOL_M",
    "TABLE",
    "Assessment",
    "ChainConfig",
    "CollisionChecker",
    "Config",
    "FloatArray",
    "Indices",
    "Invariant",
    "MarginConfig",
    "Pool",
    "Posture",
    "Projection",
    "Projector",
    "Proximity",
    "RecordingConfig",
    "RobotFiles",
    "RobotSource",
    "RouteConfig",
    "SamplingConfig",
    "Scene",
    "SegmentType",
    "Spot",
    "StanceConfig",
    "StanceSpace",
    "TableConfig",
    "Verification",
    "Worst",
    "WorstSoFar",
    "assess",
    "contact_in_table",
    "contact_placement",
    "convex_hull_clockwise",
    "flatten_on_floor",
    "is_route_file",
    "kinematic_urdf",
    "load_config",
    "load_plan",
    "load_pool",
    "parse_config",
    "plan_entries",
    "polygon_margin",
    "pool_from_dict",
    "posture_from_dict",
    "read_route",
    "route_arrays",
    "scene_for",
    "summarize",
    "tilt_angles",
    "write_pool",
    "yaw_rotation",
]
