"""``posegen measure``: a recorded rosbag2 session turned into posegen measurements."""

from __future__ import annotations

import argparse

from posegen.cli.options import DEFAULT_CONFIG, JOINT_STATES_TOPIC, session_name

NAME = "measure"
HELP = "find the static contacts in a recorded rosbag2 and write them as measurements"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("bag", help="rosbag2 directory (MCAP or sqlite3)")
    parser.add_argument("--route", default=None, help="the route the robot ran: names each contact's arm and posture")
    parser.add_argument("--config", default=DEFAULT_CONFIG, help=f"scene config (default {DEFAULT_CONFIG})")
    parser.add_argument(
        "--session", type=session_name, default=None, help="table session of the contacts (default: the bag's name)"
    )
    parser.add_argument(
        "--joint-topic", default=JOINT_STATES_TOPIC, help=f"JointState topic (default {JOINT_STATES_TOPIC})"
    )
    parser.add_argument(
        "--no-wrench", action="store_true", help="ignore the wrist wrenches: joint speed alone (needs --route)"
    )
    parser.add_argument("-o", "--output", default="plans/measurements.yaml", help="measurement file to write")


def run(args: argparse.Namespace) -> int:
    """Measure the bag and print what was kept and what was left out."""
    from posegen.calibrate import measure_bag

    measured = measure_bag(
        args.bag,
        args.output,
        config_path=args.config,
        route_path=args.route,
        session=args.session,
        joint_topic=args.joint_topic,
        use_wrench=not args.no_wrench,
    )
    source = "wrist force and joint speed" if measured.wrench_topics else "joint speed and the route"
    print(
        f"measure: {len(measured.windows)} contacts in {measured.duration_s:.1f} s ({source}), "
        f"{len(measured.rejected)} windows left out -> {measured.output}"
    )
    for tool in measured.tools:
        print(f"  {tool.chain} wrist: {tool.note}")
    for rejected in measured.rejected:
        print(f"  left out {rejected.start_s:.2f}-{rejected.end_s:.2f} s: {rejected.reason}")
    return 0
