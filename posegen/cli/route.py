"""``posegen route``: order, plan, time and export a trajectory through selected postures."""

from __future__ import annotations

import argparse
from pathlib import Path

from posegen.cli.progress import ProgressBar

NAME = "route"
HELP = "order, plan and time a trajectory through selected postures"
PROGRESS = True  # draws a progress bar (and takes -q)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("selection", nargs="?", default="plans/selected.yaml", help="selection or pool file")
    parser.add_argument("--config", default=None, help="scene config (default: the one saved in the file)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the ordering and of OMPL (default 0)")
    parser.add_argument(
        "-o", "--output", default="plans/route.yaml", help="route file, .yaml or .json (a .csv is written beside)"
    )


def run(args: argparse.Namespace) -> int:
    """Plan the route, write it and print its figures."""
    from posegen.route import route_plan_file

    with ProgressBar(args.quiet) as bar:
        routed = route_plan_file(args.selection, args.output, args.seed, args.config, bar)
    summary, order = routed.summary, routed.route.order
    print(
        f"route: {summary['routed']} of {summary['postures']} postures, {summary['points']} points, "
        f"{summary['duration_s']:.1f} s of robot time ({summary['robot_time_per_contact_s']:.1f} s per contact), "
        f"planned in {routed.planning_s:.1f} s -> {Path(args.output)} (and {routed.csv_path.name})"
    )
    print(
        f"  order: TSP {order.length_s:.1f} s vs nearest neighbour {order.nearest_neighbour_s:.1f} s "
        "(time-like distance at the velocity limits)"
    )
    for index, reason in routed.route.skipped:
        print(f"  skipped posture {index}: {reason}")
    return 0
