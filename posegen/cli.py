"""The ``posegen`` command line. The only place errors become exit codes.

Exit codes: 0 success, 1 a check found violations, 2 bad input or infeasible problem,
130 interrupted.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys

from posegen import __version__, commands
from posegen.errors import PosegenError

DEFAULT_CONFIG = "configs/talos_table.yaml"
EXIT_ERROR = 2
EXIT_INTERRUPTED = 130


def _positive(text: str) -> int:
    value = int(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be a positive integer, got {value}")
    return value


def _fraction(text: str) -> float:
    value = float(text)
    if not 0.0 < value <= 1.0:
        raise argparse.ArgumentTypeError(f"must be in (0, 1], got {value}")
    return value


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand."""
    parser = argparse.ArgumentParser(
        prog="posegen",
        description="Plan and run the whole-body geometric calibration of a humanoid touching a table.",
        epilog="pipeline: pool -> select -> route -> (record on the robot) -> calibrate; "
        "simulate rehearses it on a perturbed robot. Exit codes: 0 ok, 1 check found violations, "
        "2 bad input or infeasible problem, 130 interrupted.",
    )
    parser.add_argument("--version", action="version", version=f"posegen {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    sub = parser.add_subparsers(dest="command", required=True)

    pool = sub.add_parser("pool", help="generate feasible contact postures")
    pool.add_argument("--n", type=int, default=1500, help="number of postures (default 1500)")
    pool.add_argument("--config", default=DEFAULT_CONFIG, help=f"scene config (default {DEFAULT_CONFIG})")
    pool.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    pool.add_argument("--workers", type=_positive, default=os.cpu_count() or 1, help="processes (default: cores)")
    pool.add_argument("-o", "--output", default="plans/pool.yaml", help="pool file (default plans/pool.yaml)")
    pool.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    pool.set_defaults(run=commands.run_pool)

    check = sub.add_parser("check", help="re-verify a pool or a route from scratch (exit 1 on any violation)")
    check.add_argument("file", help="pool or route file")
    check.add_argument("--config", default=None, help="scene config (default: the one saved in the file)")
    check.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    check.set_defaults(run=commands.run_check)

    sel = sub.add_parser("select", help="choose optimal postures from a pool (IROC, DETMAX, exact k)")
    sel.add_argument("pool", nargs="?", default="plans/pool.yaml", help="pool file (default plans/pool.yaml)")
    sel.add_argument("--k", type=_positive, default=None, help="exactly K postures (default: where IROC's O1 peaks)")
    sel.add_argument("--runs", type=int, default=0, help="DETMAX runs from seeded random starts (default 0)")
    sel.add_argument("--seed", type=int, default=0, help="seed of the DETMAX starts (default 0)")
    sel.add_argument(
        "--fraction",
        type=_fraction,
        nargs="+",
        default=[0.9, 0.95],
        help="report the smallest k reaching these fractions of O1* (default 0.9 0.95)",
    )
    sel.add_argument("--config", default=None, help="scene config (default: the one saved in the pool)")
    sel.add_argument(
        "-o", "--output", default="plans/selected.yaml", help="selection file (default plans/selected.yaml)"
    )
    sel.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    sel.set_defaults(run=commands.run_select)

    rt = sub.add_parser("route", help="order, plan and time a trajectory through selected postures")
    rt.add_argument("selection", nargs="?", default="plans/selected.yaml", help="selection or pool file")
    rt.add_argument("--config", default=None, help="scene config (default: the one saved in the file)")
    rt.add_argument("--seed", type=int, default=0, help="seed of the ordering and of OMPL (default 0)")
    rt.add_argument(
        "-o", "--output", default="plans/route.yaml", help="route file, .yaml or .json (a .csv is written beside)"
    )
    rt.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    rt.set_defaults(run=commands.run_route)

    sim = sub.add_parser("simulate", help="contacts of a perturbed robot at planned postures")
    sim.add_argument("postures", help="pool or selection file")
    sim.add_argument("--config", default=DEFAULT_CONFIG, help=f"scene config (default {DEFAULT_CONFIG})")
    sim.add_argument("--seed", type=int, default=0, help="seed of the robot errors and noise (default 0)")
    sim.add_argument("--error-mm", type=float, default=2.0, help="sigma of length errors (default 2 mm)")
    sim.add_argument(
        "--error-deg", type=float, default=0.5, help="sigma of angle errors (default 0.5 deg, clipped 1.5)"
    )
    sim.add_argument("--noise-deg", type=float, default=0.005, help="encoder noise sigma (default 0.005 deg)")
    sim.add_argument("--session", default="sim", help="table session name (default sim)")
    sim.add_argument("-o", "--output", default="plans/sim/measurements.yaml", help="measurement file")
    sim.set_defaults(run=commands.run_simulate)

    cal = sub.add_parser("calibrate", help="identify the kinematics from recorded contacts")
    cal.add_argument("measurements", nargs="+", help="measurement files (posegen YAML or CSV), FILE[@SESSION]")
    cal.add_argument("--validate", nargs="*", default=[], help="held-out measurement files, FILE[@SESSION]")
    cal.add_argument("--config", default=DEFAULT_CONFIG, help=f"scene config (default {DEFAULT_CONFIG})")
    cal.add_argument(
        "--prior-scale",
        type=float,
        default=None,
        help="prior size x (1 mm, 0.1 deg); default: chosen by cross-validation",
    )
    cal.add_argument("--keep-outliers", action="store_true", help="report outliers but keep them in the fit")
    cal.add_argument("--seed", type=int, default=0, help="seed of the CV folds (default 0)")
    cal.add_argument("-o", "--output", default="plans/calibration", help="output folder (default plans/calibration)")
    cal.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    cal.set_defaults(run=commands.run_calibrate)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit code."""
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        # Before numpy loads: small matrices run faster on one BLAS thread (we parallelise
        # over processes), and results are bit-identical however the command is launched.
        os.environ.setdefault(var, "1")
    args = build_parser().parse_args(argv)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING, format="posegen: %(message)s", stream=sys.stderr
    )
    try:
        return int(args.run(args))
    except PosegenError as exc:
        print(f"posegen: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        print("posegen: interrupted; rerun the same command to resume", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # output piped into a reader that stopped early (e.g. head)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
