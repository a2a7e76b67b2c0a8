"""``posegen route``: order, plan, time and export a trajectory through selected postures."""

from __future__ import annotations

import argparse
from pathlib import Path

from posegen.cli.options import add_backend_arguments, seed
from posegen.cli.progress import ProgressBar

NAME = "route"
HELP = "order, plan and time a trajectory through selected postures"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("selection", nargs="?", default="plans/selected.yaml", help="selection or pool file")
    parser.add_argument("--config", default=None, help="scene config (default: the one saved in the file)")
    parser.add_argument("--seed", type=seed, default=0, help="seed of the ordering, OMPL and shortcuts (default 0)")
    parser.add_argument(
        "--pool",
        default=None,
        help="the selection's pool, to replace a posture that cannot be reached "
        "(default: the pool the selection records)",
    )
    parser.add_argument(
        "--csv",
        action="store_true",
        help="also write the points as CSV beside the route (OUTPUT.<hash>.csv, replaced with it as one)",
    )
    add_backend_arguments(parser)
    parser.add_argument(
        "-o",
        "--output",
        default="plans/route.yaml",
        help="route file, .yaml or .json (its arrays go to .npz beside it)",
    )


def run(args: argparse.Namespace) -> int:
    """Plan the route, write it and print its figures."""
    from posegen.parallel import open_backend
    from posegen.route import route_postures_file

    with open_backend(args.workers, args.scheduler) as backend, ProgressBar(args.quiet) as bar:
        routed = route_postures_file(
            args.selection,
            args.output,
            args.seed,
            args.config,
            bar,
            workers=backend,
            pool_path=args.pool,
            csv=args.csv,
        )
    summary, route = routed.summary, routed.route
    files = ", ".join(p.name for p in routed.written[1:])
    print(
        f"route: {summary.routed} of {summary.postures} postures ({summary.substituted} substituted), "
        f"{summary.points} points, {summary.duration_s:.1f} s of robot time "
        f"(per contact: median {summary.robot_time_per_contact_median_s:.2f} s, "
        f"mean {summary.robot_time_per_contact_s:.2f} s), planned in {routed.planning_s:.1f} s "
        f"-> {Path(args.output)} (and {files})"
    )
    print(
        f"  order: TSP {route.order.length_s:.1f} s vs nearest neighbour {route.order.nearest_neighbour_s:.1f} s "
        "(rest-to-rest times at the free speed); free motions: "
        + ", ".join(f"{k} {v}" for k, v in summary.free_motions.items())
    )
    for s in route.substitutions:
        print(
            f"  posture {s.lost} replaced by pool posture {s.substitute} (log det gain {s.gain:.2f}; the selection's "
            f"O1 {s.o1_before:.2f}, rank {s.rank_before} -> the postures routed so far with it: O1 {s.o1_after:.2f}, "
            f"rank {s.rank_after}): {s.reason}"
        )
    for index, reason in route.skipped:
        print(f"  skipped posture {index}: {reason} ({routed.repair})")
    if not route.returns:
        print("  the route ends above its last contact: no free motion back to the start posture")
    return 0
