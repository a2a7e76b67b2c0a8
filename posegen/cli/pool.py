"""``posegen pool``: generate (or resume) a pool of feasible contact postures."""

from __future__ import annotations

import argparse
from pathlib import Path

from posegen.cli.options import DEFAULT_CONFIG, add_backend_arguments, positive, seed
from posegen.cli.progress import ProgressBar

NAME = "pool"
HELP = "generate feasible contact postures"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("--n", type=positive, default=1500, help="number of postures (default 1500)")
    parser.add_argument("--config", default=DEFAULT_CONFIG, help=f"scene config (default {DEFAULT_CONFIG})")
    parser.add_argument("--seed", type=seed, default=0, help="random seed (default 0)")
    add_backend_arguments(parser)
    parser.add_argument("-o", "--output", default="plans/pool.yaml", help="pool file (default plans/pool.yaml)")


WORKER_MODULES = ("posegen.pool.generation",)  # what a worker's sampling job imports


def run(args: argparse.Namespace) -> int:
    """Generate the pool and print its summary."""
    from posegen.parallel import open_backend

    # the workers' imports (placo, pinocchio, coal) start first, in the forkserver, beside this process's own
    with open_backend(args.workers, args.scheduler, preload=WORKER_MODULES) as backend, ProgressBar(args.quiet) as bar:
        from posegen.pool import generate_pool_file

        pool = generate_pool_file(args.config, args.output, args.n, args.seed, backend, bar)
    rate = 100.0 * len(pool.postures) / max(pool.attempted, 1)
    print(
        f"pool: {len(pool.postures)} postures accepted of {pool.attempted} samples ({rate:.1f}%) -> {Path(args.output)}"
    )
    print("rejected: " + (", ".join(f"{k} {v}" for k, v in pool.rejected.items()) or "none"))
    for spot, counts in pool.per_spot().items():
        print(f"  {spot}: " + ", ".join(f"{chain} {n}" for chain, n in counts.items()))
    return 0
