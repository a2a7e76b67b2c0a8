"""``posegen select``: choose optimal postures from a pool (IROC, DETMAX, exact k)."""

from __future__ import annotations

import argparse

from posegen.cli.options import fraction, non_negative, positive, seed
from posegen.cli.progress import ProgressBar
from posegen.errors import InputError

NAME = "select"
HELP = "choose optimal postures from a pool (IROC, DETMAX, exact k)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("pool", nargs="?", default="plans/pool.yaml", help="pool file (default plans/pool.yaml)")
    parser.add_argument("--k", type=positive, default=None, help="exactly K postures (default: where IROC's O1 peaks)")
    parser.add_argument(
        "--runs", type=non_negative, default=0, help="DETMAX runs from seeded random starts (default 0)"
    )
    parser.add_argument("--seed", type=seed, default=0, help="seed of the DETMAX starts (default 0)")
    parser.add_argument(
        "--fraction",
        type=fraction,
        nargs="+",
        default=[0.9, 0.95],
        help="report the smallest k reaching these fractions of O1* (default 0.9 0.95)",
    )
    parser.add_argument(
        "--given",
        nargs="+",
        default=[],
        help="measurement files already recorded (FILE[@SESSION]): choose the next --k (default 10) postures that "
        "shrink the predicted error of the weakest chain most",
    )
    parser.add_argument(
        "--calibration", default=None, help="with --given: their calibration.yaml (its model and weakest chain)"
    )
    parser.add_argument("--config", default=None, help="scene config (default: the one saved in the pool)")
    parser.add_argument(
        "-o", "--output", default="plans/selected.yaml", help="selection file (default plans/selected.yaml)"
    )


def run(args: argparse.Namespace) -> int:
    """Select, write the selection and print its figures."""
    from posegen.select import SelectionSettings, follow_up_pool_file, select_pool_file

    if args.given:
        following = follow_up_pool_file(
            args.pool, args.output, args.given, args.calibration, args.k or 10, args.config
        ).figures
        print(
            f"select: {following.selected} of {following.pool_postures} postures to follow up "
            f"{following.given_contacts} measured contacts, for chain '{following.weakest_chain}' "
            f"({following.weakest_from}) -> {args.output}"
        )
        for chain, (before, after) in following.predicted_height_sigma_mm.items():
            print(f"  predicted height sigma (model), {chain}: {before:.2f} -> {after:.2f} mm")
        return 0
    if args.calibration:
        raise InputError("--calibration goes with --given (the measurements it calibrated)")
    settings = SelectionSettings(k=args.k, runs=args.runs, seed=args.seed, fractions=tuple(args.fraction))
    with ProgressBar(args.quiet) as bar:
        selection = select_pool_file(args.pool, args.output, settings, args.config, bar)
    fig = selection.figures
    print(
        f"select: {fig.selected} of {fig.pool_postures} postures ({selection.method.value}), O1 {fig.o1:.2f} = "
        f"{100 * fig.o1_over_o1_star:.1f}% of O1* {fig.o1_star:.2f}; identifies {fig.rank} of "
        f"{fig.base_parameters} base parameters -> {args.output}"
    )
    cert = fig.certificate
    print(
        f"  weights: Kiefer-Wolfowitz gap {cert.kiefer_wolfowitz_gap:.1e} (D-efficiency >= "
        f"{cert.d_efficiency_at_least:.5f}); IROC stops at k = {fig.iroc.selected_k}; "
        + "; ".join(
            f"{100 * float(f):g}% of O1* at k = {k}" for f, k in fig.iroc.k_reaching_fraction_of_o1_star.items()
        )
    )
    if fig.detmax.runs:
        print(f"  DETMAX best of {fig.detmax.runs} (k = {fig.selected}): O1 {fig.detmax.best_o1:.2f}")
    if fig.rank < fig.base_parameters:
        print(
            f"  warning: {fig.selected} postures identify only {fig.rank} of {fig.base_parameters} base "
            "parameters; translation parameters are seen through heights only (one per posture): choose a larger k"
        )
    return 0
