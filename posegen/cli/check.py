"""``posegen check``: re-verify a pool or a route from scratch; exit 1 on any violation."""

from __future__ import annotations

import argparse

from posegen.cli.options import EXIT_VIOLATIONS, add_backend_arguments
from posegen.cli.progress import ProgressBar

NAME = "check"
HELP = "re-verify a pool or a route from scratch (exit 1 on any violation)"
PROGRESS = True  # draws a progress bar (and takes -q)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("file", help="pool or route file")
    parser.add_argument("--config", default=None, help="scene config (default: the one saved in the file)")
    add_backend_arguments(parser)


def run(args: argparse.Namespace) -> int:
    """Check the file and print the worst case of each invariant."""
    from posegen.errors import InputError
    from posegen.parallel import open_backend
    from posegen.pool import check_pool_file
    from posegen.robot import is_route_file
    from posegen.route import check_route_file

    is_route = is_route_file(args.file)
    if is_route and args.scheduler:
        raise InputError("--scheduler applies to pool files; a route file is checked on this machine")
    with ProgressBar(args.quiet) as bar:
        if is_route:
            result = check_route_file(args.file, args.config, bar)
        else:
            with open_backend(args.workers, args.scheduler) as backend:
                result = check_pool_file(args.file, args.config, bar, backend)
    unit = "point" if is_route else "posture"
    print(f"checked {result.checked} {unit}s of {args.file} (meshes, pinocchio; not the planner's word)")
    for worst in result.worst:
        status = "OK  " if worst.violations == 0 else "FAIL"
        print(
            f"  {status} {worst.invariant.value:<13} violations {worst.violations:>4}  "
            f"worst: {unit} {worst.posture} ({worst.detail})"
        )
    return 0 if result.ok else EXIT_VIOLATIONS
