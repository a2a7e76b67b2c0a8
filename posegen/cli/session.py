"""``posegen session``: an experiment batch by batch, until the predicted error meets the target or stops falling."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from posegen.cli.export import SEGMENTS_TOPIC, TRAJECTORY_TOPIC
from posegen.cli.options import JOINT_STATES_TOPIC, non_negative, positive, positive_size, seed, size, usable_cores

NAME = "session"
HELP = "an experiment batch by batch: start, add each recorded bag, status; rehearse on a simulated robot"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommands and their arguments."""
    parser.add_argument("-q", "--quiet", action="store_true", default=argparse.SUPPRESS, help="no progress output")
    steps = parser.add_subparsers(dest="step", required=True, parser_class=type(parser))
    start = steps.add_parser("start", help="the first batch: chosen, routed, checked, exported as a rosbag2 to play")
    start.add_argument("pool", help="pool file (posegen pool)")
    start.add_argument("-o", "--output", required=True, metavar="SESSION", help="session folder to create")
    start.add_argument(
        "--target-mm", type=positive_size, default=4.0, help="stop at this predicted height error (default 4 mm)"
    )
    start.add_argument("--seed", type=seed, default=0, help="seed of the routes and the CV folds (default 0)")
    start.add_argument(
        "--margin", type=size, default=0.2, help="first batch: (1 + margin) x the fewest identifying postures (0.2)"
    )
    start.add_argument("--batch", type=positive, default=10, help="postures of each next batch (default 10)")
    start.add_argument(
        "--patience",
        type=non_negative,
        default=2,
        help="stop at the deliverable's floor after this many batches without a new low above the target "
        "(default 2; 0: only the target stops the session)",
    )
    start.add_argument(
        "--deliverable",
        choices=("urdf", "compensated"),
        default="urdf",
        help="whose predicted error stops the session: calibrated.urdf alone (any stack, default) or the URDF "
        "with its compliance compensation (when the calibration ships it)",
    )
    start.add_argument("--candidates", nargs="+", default=[], help="the calibrations' candidate models (default: all)")
    start.add_argument("--fold-seeds", type=positive, default=None, help="repetitions of the calibrations' CV")
    add = steps.add_parser("add", help="measure a recorded batch, calibrate, and say done or plan the next batch")
    add.add_argument("session", help="session folder")
    add.add_argument("bag", help="the rosbag2 the robot recorded while playing the last batch")
    add.add_argument("--new-table", action="store_true", help="the table was moved: its own plane from this bag on")
    status = steps.add_parser("status", help="contacts, predicted error per chain over the batches (plot), robot time")
    status.add_argument("session", help="session folder")
    status.add_argument("--plot", default=None, help="the plot's file (default SESSION/status.png)")
    rehearse = steps.add_parser("rehearse", help="play every batch on a simulated robot until done")
    rehearse.add_argument("session", help="session folder (posegen session start)")
    rehearse.add_argument("--seed", type=seed, required=True, help="seed of the simulated robot and its noise")
    rehearse.add_argument("--compliance", type=size, default=0.0, help="true hip compliance, rad/kN m (default 0)")
    rehearse.add_argument(
        "--contact-noise-mm",
        type=size,
        default=None,
        help="sigma of each contact's local table height, mm (default 3: the real recordings')",
    )
    rehearse.add_argument(
        "--contact-noise-deg",
        type=size,
        default=None,
        help="sigma of each contact's local table roll and pitch, deg (default 0.3: the real recordings')",
    )
    rehearse.add_argument("--max-batches", type=positive, default=20, help="batches to add at most (default 20)")
    for sub in (start, add, status, rehearse):
        sub.add_argument("-q", "--quiet", action="store_true", help="no progress output")
        if sub is not status:
            sub.add_argument(
                "--workers", type=positive, default=usable_cores(), help="local worker processes (default: cores)"
            )


def run(args: argparse.Namespace) -> int:
    """Run the step and print what it did."""
    from posegen.parallel import open_backend
    from posegen.session import (
        Deliverable,
        Robot,
        SessionSettings,
        read_index,
        rehearse_session,
        session_status,
        start_session,
    )

    if args.step == "status":
        return _status(session_status(args.session, args.plot))
    with open_backend(args.workers) as backend:
        if args.step == "start":
            settings = SessionSettings(
                target_mm=args.target_mm,
                seed=args.seed,
                margin=args.margin,
                batch_postures=args.batch,
                patience=args.patience,
                deliverable=Deliverable(args.deliverable),
                candidates=tuple(args.candidates),
                fold_seeds=args.fold_seeds,
                joint_topic=JOINT_STATES_TOPIC,
                trajectory_topic=TRAJECTORY_TOPIC,
                segments_topic=SEGMENTS_TOPIC,
            )
            index = start_session(args.pool, args.output, settings, backend)
            _planned(args.output, index.batches[-1])
            return 0
        report, missing = _report_writer(backend)
        if args.step == "add":
            from posegen.session import add_bag

            _added(args.session, add_bag(args.session, args.bag, backend, args.new_table, report))
            _say_missing(missing)
            return 0
        noise = {"contact_noise_mm": args.contact_noise_mm, "contact_noise_deg": args.contact_noise_deg}
        robot = Robot(
            seed=args.seed,
            compliance_rad_per_knm=args.compliance,
            **{k: v for k, v in noise.items() if v is not None},  # None: the real recordings' figures
        )
        added = rehearse_session(
            args.session, robot, backend, args.max_batches, lambda a: _added(args.session, a), report
        )
    _say_missing(missing)
    if not added:
        verdict = "is done" if read_index(Path(args.session)).done else "stopped at the floor"
        print(f"session: {args.session} {verdict} already: nothing to rehearse")
    elif not added[-1].index.ended:
        print(f"session: not done after {len(added)} rehearsed batches (--max-batches {args.max_batches})")
    return 0


def _report_writer(backend: Any) -> tuple[Any, Exception | None]:
    """What writes each calibration's report.html into its staging folder (its figures on ``backend``'s workers).

    None, and why, without ``[view]``.
    """
    from posegen.errors import ExtraError

    try:
        from posegen.view import write_report_into
    except ExtraError as exc:  # the calibration needs no viewer: only its HTML report does
        return None, exc

    def report(staging: Path, destination: Path) -> object:
        return write_report_into(staging, None, shown_as=destination, backend=backend)

    return report, None


def _say_missing(missing: Exception | None) -> None:
    if missing is not None:
        print(f"posegen: report.html not written: {missing}", file=sys.stderr)


def _planned(session: str, batch: Any) -> None:
    print(
        f"session: batch {batch.number}: {len(batch.pool_rows)} postures, {batch.planned_s:.0f} s of robot time "
        f"-> play {session}/{batch.folder}/route_bag/, then: posegen session add {session} RECORDED_BAG"
    )


def _added(session: str, added: Any) -> None:
    """Print a batch's verdict and what comes next."""
    from posegen.calibrate import file_lines, read_summary

    batch, index = added.batch, added.index
    recording, assessment = batch.recording, batch.assessment
    missing = f", {len(recording.missing)} planned postures not recorded" if recording.missing else ""
    print(f"session: batch {batch.number}: {recording.contacts} contacts in {recording.duration_s:.0f} s{missing}")
    target = index.settings.target_mm
    if assessment.error:
        print(f"  no calibration yet: {assessment.error}")
    else:
        folder = f"{session}/{batch.folder}/calibration"
        print(
            f"  calibrated on {assessment.contacts} contacts; the files written (mean absolute z mm / roll deg / "
            "pitch deg, as calibrate reports them):"
        )
        for line in file_lines(read_summary(f"{folder}/calibration.yaml")):
            print(f"  {line}")
        deliverable = f"{assessment.deliverable} deliverable ({assessment.candidate})"
        print(f"  the session follows the {deliverable}: its predicted held-out height error against the target:")
        for chain, error in assessment.predicted_z_mm.items():
            verdict = "ok" if error <= target else "above"
            print(f"    {chain}: {error:.2f} mm ({verdict} the target {target:g} mm)")
        for chain, before, after in index.stalled:
            print(
                f"  {chain}: no gain from the last batch ({before:.2f} -> {after:.2f} mm): the "
                f"{assessment.deliverable} deliverable may be at its floor (a URDF cannot hold compliant "
                "joints; a session started with --deliverable compensated follows the compensated files)"
            )
    if added.next_batch is None and index.at_floor:
        print(
            f"session: stopped at the floor: no chain above the target {target:g} mm reached a new low in the last "
            f"{index.settings.patience} batches -> the deliverables are in {session}/{batch.folder}/calibration/"
        )
        return
    if added.next_batch is None:
        print(f"session: done -> the deliverables are in {session}/{batch.folder}/calibration/")
        return
    _planned(session, added.next_batch)


def _verdict(index: Any) -> str:
    return "done" if index.done else "stopped at the floor" if index.at_floor else "not done"


def _status(status: Any) -> int:
    index = status.index
    print(
        f"session: {len(index.batches)} batches, {status.contacts} contacts; robot time {status.spent_s:.0f} s spent, "
        f"{status.planned_s:.0f} s planned; {_verdict(index)} "
        f"(target {index.settings.target_mm:g} mm, {index.settings.deliverable.value} deliverable)"
    )
    for batch in index.batches:
        line = f"  batch {batch.number}: {batch.state.value}, {len(batch.pool_rows)} postures"
        if batch.recording is not None:
            line += f", {batch.recording.contacts} contacts"
        if batch.assessment is not None and not batch.assessment.error:
            errors = ", ".join(f"{c} {v:.2f} mm" for c, v in batch.assessment.predicted_z_mm.items())
            line += f"; predicted {errors} after {batch.assessment.contacts} contacts"
        print(line)
    if status.plot is not None:
        print(f"  -> {status.plot}")
    return 0
