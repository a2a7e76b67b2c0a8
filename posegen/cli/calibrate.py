"""``posegen calibrate``: identify the kinematics from recorded contacts."""

from __future__ import annotations

import argparse

from posegen.cli.options import DEFAULT_CONFIG
from posegen.cli.progress import ProgressBar

NAME = "calibrate"
HELP = "identify the kinematics from recorded contacts"
PROGRESS = True  # draws a progress bar (and takes -q)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument("measurements", nargs="+", help="measurement files (posegen YAML or CSV), FILE[@SESSION]")
    parser.add_argument("--validate", nargs="*", default=[], help="held-out measurement files, FILE[@SESSION]")
    parser.add_argument("--config", default=DEFAULT_CONFIG, help=f"scene config (default {DEFAULT_CONFIG})")
    parser.add_argument(
        "--prior-scale",
        type=float,
        default=None,
        help="prior size x (1 mm, 0.1 deg); default: chosen by cross-validation",
    )
    parser.add_argument("--keep-outliers", action="store_true", help="report outliers but keep them in the fit")
    parser.add_argument("--seed", type=int, default=0, help="seed of the CV folds (default 0)")
    parser.add_argument("-o", "--output", default="plans/calibration", help="output folder (default plans/calibration)")


def run(args: argparse.Namespace) -> int:
    """Calibrate, write the calibration folder and its HTML report, and print the before/after table."""
    from posegen.calibrate import Settings, calibrate_files, format_table
    from posegen.view import write_report

    settings = Settings(kappa=args.prior_scale, drop_outliers=not args.keep_outliers, seed=args.seed)
    with ProgressBar(args.quiet) as bar:
        calibrated = calibrate_files(args.measurements, args.validate, args.output, settings, args.config, bar)
    report = calibrated.report
    base = report["base_parameters"]
    print(
        f"calibrate: {calibrated.training_contacts} training contacts, {base['total']} base parameters "
        f"(robot per chain: {base['robot_parameters_per_chain']}), prior x{report['weights']['prior_length_mm']:g}"
    )
    for message in report["rejected_rows"]:
        print(f"  row left out: {message}")
    for outlier in report["outliers"]:
        print(f"  outlier left out: {outlier['contact']} (normalised CV residual {outlier['normalised_cv_residual']})")
    print(format_table(report))
    report_path = write_report(args.output, args.config)
    print(
        f"-> {args.output}/ (calibration.yaml, calibrated.urdf, calibrated.yaml, residuals.csv, posterior.npz, "
        f"parameters.png, residuals.png, {report_path.name})"
    )
    return 0
