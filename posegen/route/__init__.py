"""Stage 3: a robot-ready trajectory through the selected postures.

The visiting order (TSP), geometric paths in the stance space (vertical approach and
contact, free motions by straight lines, via postures or OMPL), toppra timing, the ROS 2
``JointTrajectory`` export, and the independent check of every exported point.
"""

from posegen.route.check import RouteInvariant, verify_route
from posegen.route.export import route_to_dict, write_route
from posegen.route.motion import Vertical, plan_free, seed_planner, straight, vertical_paths
from posegen.route.ordering import Order, order_postures, time_distances
from posegen.route.route import Route, Segment, plan_route, start_posture
from posegen.route.timing import SAFETY, Timed, hold, parameterize
from posegen.route.workflow import Exported, Routed, check_route_file, export_route_bag, route_plan_file

__all__ = [
    "SAFETY",
    "Exported",
    "Order",
    "Route",
    "RouteInvariant",
    "Routed",
    "Segment",
    "Timed",
    "Vertical",
    "check_route_file",
    "export_route_bag",
    "hold",
    "order_postures",
    "parameterize",
    "plan_free",
    "plan_route",
    "route_plan_file",
    "route_to_dict",
    "seed_planner",
    "start_posture",
    "straight",
    "time_distances",
    "verify_route",
    "vertical_paths",
    "write_route",
]
