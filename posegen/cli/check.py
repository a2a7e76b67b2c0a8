"""``posegen check``: re-verify a pool, a selection or a route from scratch; exit 1 on any violation."""

from __future__ import annotations

import argparse

from posegen.cli.options import EXIT_VIOLATIONS, add_backend_arguments, positive_size
from posegen.cli.progress import ProgressBar

NAME = "check"
HELP = "re-verify a pool, a selection or a route from scratch (exit 1 on any violation)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("file", help="pool, selection or route file")
    parser.add_argument("--config", default=None, help="scene config (default: the one saved in the file)")
    parser.add_argument(
        "--min-dt",
        type=positive_size,
        default=None,
        help="route: smallest time step between points in s (default 0.001)",
    )
    add_backend_arguments(parser)


def run(args: argparse.Namespace) -> int:
    """Check the file and print the worst case of each invariant (and, for a route, the first violations)."""
    from posegen.io import is_route_file
    from posegen.parallel import open_backend
    from posegen.pool import check_pool_file
    from posegen.route import MIN_DT_S, check_route_file

    is_route = is_route_file(args.file)
    with ProgressBar(args.quiet) as bar, open_backend(args.workers, args.scheduler) as backend:
        if is_route:
            min_dt = MIN_DT_S if args.min_dt is None else args.min_dt
            result = check_route_file(args.file, args.config, bar, backend, min_dt)
        else:
            result = check_pool_file(args.file, args.config, bar, backend)
    unit = "point" if is_route else "posture"
    geometry = "collision geometry" if result.geometry is None else result.geometry.describe()
    print(f"checked {result.checked} {unit}s of {args.file} ({geometry}; pinocchio; not the planner's word)")
    if result.geometry is not None and result.geometry.bare_links:
        bare = result.geometry.bare_links
        print(f"  WARN {len(bare)} moving links have no collision geometry (nothing collides with them):", *bare)
    for worst in result.worst:
        if not worst.checked:
            print(f"  SKIP {worst.invariant.value:<15} {worst.detail}")
            continue
        status = "OK  " if worst.violations == 0 else "FAIL"
        if not is_route:
            print(
                f"  {status} {worst.invariant.value:<15} violations {worst.violations:>4}  "
                f"worst: {unit} {worst.posture} ({worst.detail})"
            )
            continue
        print(f"  {status} {worst.invariant.value:<15} violations {worst.violations:>4}  ({worst.detail})")
        for example in worst.examples[1:] if worst.examples[:1] == (worst.detail,) else worst.examples:
            print(f"         {example}")
    if result.efforts:
        print("  worst holding torque per joint (x its effort limit):")
        for effort in sorted(result.efforts, key=lambda e: -e.ratio):
            print(
                f"    {effort.joint:<24} {effort.ratio:6.3f}  ({effort.torque_nm:7.2f} of {effort.limit_nm:g} N m, "
                f"point {effort.point})"
            )
    return 0 if result.ok else EXIT_VIOLATIONS
