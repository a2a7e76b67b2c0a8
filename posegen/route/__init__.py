"""Stage 3: a robot-ready trajectory through the selected postures.

The visiting order (TSP on rest-to-rest times), stops and transfers planned over worker
processes (vertical approach and contact; free motions by straight lines, via states or
OMPL, shortened and blended), one toppra timing per transfer, the repair of a selection
whose posture cannot be reached, the route file (:class:`posegen.io.Route`, written by
:mod:`posegen.io`), and the independent check of every exported point.

Internal: scripts use the public API at ``posegen.`` (stable, documented with examples); the
names here are its plumbing and may change between versions.
"""

from posegen.route.check import MIN_DT_S, RouteInvariant, verify_route
from posegen.route.export import route_arrays_of, route_artefact
from posegen.route.free_motion import FreeMotion, Method, free_motions, plan_free, raised_midpoints, via_sequences
from posegen.route.motion import Vertical, follow, straight, through, vertical_paths
from posegen.route.ordering import Order, order_postures, rest_to_rest_time, transfer_times
from posegen.route.planner import START, Planner, Stop, Transfer, plan_stop, plan_transfer, start_posture
from posegen.route.pose_check import PoseInvariant, check_poses
from posegen.route.repair import Substitutes, Substitution, insertion_places, ranked_substitutes
from posegen.route.route import PlannedRoute, plan_route
from posegen.route.smoothing import blend_corners, corners, path_length, shortcut
from posegen.route.summary import RouteSummary, summarize
from posegen.route.timing import SAFETY, Timed, hold, parameterize
from posegen.route.unplanned import Unplanned, UnplannedCause
from posegen.route.workflow import Exported, Routed, check_route_file, export_route_bag, route_postures_file

__all__ = [
    "MIN_DT_S",
    "SAFETY",
    "START",
    "Exported",
    "FreeMotion",
    "Method",
    "Order",
    "PlannedRoute",
    "Planner",
    "PoseInvariant",
    "RouteInvariant",
    "RouteSummary",
    "Routed",
    "Stop",
    "Substitutes",
    "Substitution",
    "Timed",
    "Transfer",
    "Unplanned",
    "UnplannedCause",
    "Vertical",
    "blend_corners",
    "check_poses",
    "check_route_file",
    "corners",
    "export_route_bag",
    "follow",
    "free_motions",
    "hold",
    "insertion_places",
    "order_postures",
    "parameterize",
    "path_length",
    "plan_free",
    "plan_route",
    "plan_stop",
    "plan_transfer",
    "raised_midpoints",
    "ranked_substitutes",
    "rest_to_rest_time",
    "route_arrays_of",
    "route_artefact",
    "route_postures_file",
    "shortcut",
    "start_posture",
    "straight",
    "summarize",
    "through",
    "transfer_times",
    "verify_route",
    "vertical_paths",
    "via_sequences",
]
