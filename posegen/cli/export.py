"""``posegen export``: a route as a rosbag2 a ROS 2 robot can play."""

from __future__ import annotations

import argparse

NAME = "export"
HELP = "write a route as a rosbag2 (JointTrajectory per segment and whole, segment table)"

TRAJECTORY_TOPIC = "/joint_trajectory_controller/joint_trajectory"  # ros2_control's trajectory controller
SEGMENTS_TOPIC = "/posegen/segments"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("route", help="route file (posegen route)")
    parser.add_argument("--bag", required=True, metavar="DIR", help="rosbag2 directory to write (MCAP storage)")
    parser.add_argument("--topic", default=TRAJECTORY_TOPIC, help=f"JointTrajectory topic (default {TRAJECTORY_TOPIC})")
    parser.add_argument(
        "--segments-topic", default=SEGMENTS_TOPIC, help=f"segment table topic (default {SEGMENTS_TOPIC})"
    )


def run(args: argparse.Namespace) -> int:
    """Export the route and say what was written."""
    from posegen.route import export_route_bag

    exported = export_route_bag(args.route, args.bag, args.topic, args.segments_topic)
    print(
        f"export: {exported.points} points in {exported.segments} segments -> {exported.bag}/ "
        f"({exported.messages} messages on {args.topic} and {args.segments_topic})"
    )
    return 0
