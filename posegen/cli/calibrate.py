"""``posegen calibrate``: identify the kinematics from recorded contacts."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from posegen.cli.options import DEFAULT_CONFIG, positive, positive_size, seed, usable_cores
from posegen.cli.progress import ProgressBar

if TYPE_CHECKING:
    from posegen.calibrate import Calibrated
    from posegen.parallel import Backend

NAME = "calibrate"
HELP = "identify the kinematics from recorded contacts"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the command's arguments."""
    parser.add_argument(
        "measurements", nargs="+", help="measurement files (posegen YAML or CSV), FILE[@SESSION] ('@' of a name: '@@')"
    )
    parser.add_argument(
        "--validate", nargs="*", default=[], help="held-out measurement files, FILE[@SESSION] ('@' of a name: '@@')"
    )
    parser.add_argument(
        "--config",
        default=None,
        help=f"scene config (default: the one saved in the measurement files; for CSV files {DEFAULT_CONFIG})",
    )
    parser.add_argument(
        "--prior-scale",
        type=positive_size,
        default=None,
        help="fix the prior scale (x calibration.prior of the config); default: chosen by cross-validation",
    )
    parser.add_argument(
        "--candidates", nargs="+", default=[], help="only these of the config's candidate models (default: all)"
    )
    parser.add_argument(
        "--fold-seeds", type=positive, default=None, help="repetitions of the CV (default: the config's)"
    )
    parser.add_argument("--keep-outliers", action="store_true", help="report bad rows but keep them in the fit")
    parser.add_argument("--seed", type=seed, default=0, help="first seed of the CV folds (default 0)")
    parser.add_argument(
        "--workers",
        type=positive,
        default=usable_cores(),
        help="processes the candidate models are cross-validated on (default: cores; the same result for any count)",
    )
    parser.add_argument("-o", "--output", default="plans/calibration", help="output folder (default plans/calibration)")


def run(args: argparse.Namespace) -> int:
    """Calibrate, write the calibration folder and its HTML report, and print the files written first."""
    from posegen.parallel import open_backend

    # the workers' imports (the report's figures are drawn there too) start first, beside this process's own:
    # a module an extra lacks is skipped there, and named here when the report needs it
    preload = ("posegen.calibrate.model_selection", "matplotlib.pyplot", "posegen.view.report_figures")
    with ProgressBar(args.quiet) as bar, open_backend(args.workers, preload=preload) as backend:
        calibrated, missing = _calibrate(args, bar, backend)
    _print(calibrated, args.output, missing)
    return 0


def _calibrate(args: argparse.Namespace, bar: ProgressBar, backend: Backend) -> tuple[Calibrated, Exception | None]:
    """Calibrate on ``backend`` and write the folder (with its report unless the viewer's extra is missing)."""
    from posegen.calibrate import Settings, calibrate_files
    from posegen.errors import ExtraError

    settings = Settings(
        prior_scale=args.prior_scale,
        candidates=tuple(args.candidates),
        fold_seeds=args.fold_seeds,
        drop_outliers=not args.keep_outliers,
        seed=args.seed,
    )
    config = args.config or (None if _any_posegen_file(args.measurements) else DEFAULT_CONFIG)
    missing: list[ExtraError] = []

    def report_html(folder: Path) -> object:
        # the viewer is imported only now, while the workers draw the plots: the calibration needs none of it
        try:
            from posegen.view import write_report_into
        except ExtraError as exc:  # no viewer: the folder goes without its report, and the command says so
            missing.append(exc)
            return None
        return write_report_into(folder, args.config, shown_as=args.output, backend=backend)

    calibrated = calibrate_files(
        args.measurements, args.validate, args.output, settings, config, bar, backend, report_html
    )
    return calibrated, (missing[0] if missing else None)


def _print(calibrated: Calibrated, output: str, missing: Exception | None) -> None:
    """The files written first (each judged as a stack loading it sees it), the model, the rows, what to load."""
    from posegen.calibrate import DeliverableKind, file_lines, format_table, load_line, model_line

    summary = calibrated.summary
    kept = calibrated.training_contacts - sum(1 for row in summary.left_out if not row.kept)
    print(
        f"calibrate: {calibrated.training_contacts} training contacts ({kept} kept); the files written, each judged "
        "as a stack loading it sees it (mean absolute z mm / roll deg / pitch deg):"
    )
    for line in file_lines(summary):
        print(line)
    print(model_line(summary))
    for message in summary.rejected_rows:
        print(f"  row left out: {message}")
    for row in summary.left_out:
        action = "flagged, kept" if row.kept else "left out"
        print(f"  row {action}: {row.file}:{row.line} ({row.spot}): {row.reason} {row.value}")
    for warning in summary.warnings:
        print(f"  warning: {warning}")
    print(format_table(summary))
    report_name = "no report.html" if missing else "report.html"
    print(
        f"-> {output}/ (calibration.yaml, calibrated.urdf, calibrated.yaml, offsets.yaml, residuals.csv, "
        f"posterior.npz, parameters.png, residuals.png, cross_validation.png, {report_name}"
        + (", with_compliance/" if DeliverableKind.COMPENSATED in summary.deliverables else "")
        + ")"
    )
    print(load_line(summary))
    if missing:
        print(f"posegen: report.html not written: {missing}", file=sys.stderr)


def _any_posegen_file(items: list[str]) -> bool:
    """Whether a measurement file is posegen's (YAML, with its scene config) rather than a recorded CSV."""
    from posegen.model import measurement_item

    return any(not measurement_item(item)[0].lower().endswith(".csv") for item in items)
