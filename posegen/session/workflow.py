"""The session's commands, from files to files: ``posegen session start``, ``add``, ``status``.

Every step writes its new files first and the index last (:mod:`posegen.session.index`),
under the session folder's lock: killed anywhere, the folder is the one before the step
(plus leftovers the index does not name, made again), and the same command finishes it.
The error that stops a session is the one ``calibrate`` reports: the repeated grouped
cross-validation's predicted held-out height error (mean absolute, per chain) of the
deliverable the session was started for.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from posegen.calibrate import DeliverableKind, Settings, calibrate_files, measure_bag
from posegen.errors import ArgumentError, InfeasibleError, InputError, OutputError, unknown_name
from posegen.io import OutputKind, RecordedBag, check_writable, claim_output, load_pool, write_yaml
from posegen.parallel import Backend
from posegen.robot import load_config, scene_for_postures
from posegen.session.batch import (
    CALIBRATION_FOLDER,
    MEASUREMENTS_FILE,
    ROUTE_FILE,
    SELECTION_FILE,
    BatchSources,
    missing_rows,
    route_batch,
    select_first,
    select_next,
)
from posegen.session.index import (
    INDEX_FILE,
    Assessment,
    Batch,
    BatchState,
    Recording,
    SessionIndex,
    SessionSettings,
    batch_folder,
    check_files,
    check_settings,
    sha256_of,
    table_name,
    write_index,
)
from posegen.session.index_reader import read_index

CONFIG_FILE = "config.yaml"
Report = Callable[[Path, Path], object]  # writes a calibration's report into its staging folder (staging, destination)


@dataclass(frozen=True)
class Added:
    """What ``posegen session add`` did."""

    batch: Batch  # the batch the bag was added to (recorded and assessed)
    next_batch: Batch | None  # planned to play next; None when done
    index: SessionIndex


def start_session(pool_path: str, output: str, settings: SessionSettings, backend: Backend) -> SessionIndex:
    """Start a session: the first batch chosen, routed, checked and exported as a rosbag2 to play.

    Raises:
        PosegenError: Bad settings or pool, a folder that already holds a session, or a
            first batch that cannot be routed.

    """
    check_settings(settings)
    folder = Path(output)
    check_writable(folder, OutputKind.FOLDER)
    if (folder / INDEX_FILE).exists():
        raise InputError(
            f"{folder} already holds a session: add bags with posegen session add, or choose another output",
            parameter="output",
        )
    _check_empty(folder)
    pool = load_pool(pool_path)
    scene = scene_for_postures(pool, pool_path, None)
    if not pool.postures:
        raise InfeasibleError(f"{pool_path}: the pool is empty")
    names = [c.name for c in scene.calibration.candidates]
    for name in settings.candidates:
        if name not in names:
            raise ArgumentError(f"candidates: {unknown_name('candidate model', name, names)}", parameter="candidates")
    pool_abs = str(Path(pool_path).resolve())
    created = not folder.exists()
    with claim_output(folder, OutputKind.FOLDER):
        try:
            write_yaml(folder / CONFIG_FILE, scene.config.to_dict())
            select_first(pool_abs, pool, folder / batch_folder(1) / SELECTION_FILE, settings)
            batch = route_batch(folder, 1, pool_abs, settings, backend)
        except BaseException:  # nothing of a first batch is kept: the same command starts it again
            shutil.rmtree(folder / batch_folder(1), ignore_errors=True)
            (folder / CONFIG_FILE).unlink(missing_ok=True)
            if created and folder.is_dir() and not any(folder.iterdir()):
                folder.rmdir()  # nor the folder this start made
            raise
        batch = replace(batch, files={**batch.files, CONFIG_FILE: sha256_of(folder / CONFIG_FILE)})
        index = SessionIndex(scene.provenance(settings.seed), pool_abs, sha256_of(Path(pool_abs)), settings, (batch,))
        write_index(folder, index)
    return index


def _check_empty(folder: Path) -> None:
    """A new session's folder holds nothing but what a killed ``start`` left (its config and first batch).

    Raises:
        OutputError: It holds anything else: never written into.

    """
    left = {CONFIG_FILE, batch_folder(1)}
    if folder.is_dir():
        others = sorted(p.name for p in folder.iterdir() if p.name not in left and not p.name.startswith("."))
        if others:
            raise OutputError(
                f"{folder} holds files posegen did not write ({', '.join(others[:3])}): not writing a session "
                "into it; give a new folder",
                parameter="output",
            )


def open_session(folder: Path) -> SessionIndex:
    """Read a session's index and check its files and its pool.

    Raises:
        InputError: Not a session, a malformed index, a file of it (or its pool) changed or
            missing, or candidate models its config lacks.

    """
    index = read_index(folder)
    check_files(folder, index)
    pool = Path(index.pool)
    if not pool.is_file() or sha256_of(pool) != index.pool_sha256:
        raise InputError(f"{pool}: the session's pool is missing or changed since the session started (sha256)")
    names = [c.name for c in load_config(folder / CONFIG_FILE).calibration.candidates]
    for name in index.settings.candidates:
        if name not in names:
            raise InputError(
                f"{folder / INDEX_FILE}: settings.candidates: {unknown_name('candidate model', name, names)}"
            )
    return index


def _check_bag(index: SessionIndex, folder: Path, recorded: RecordedBag, digest: str) -> Batch:
    """The batch a bag is added to (the last), after checking that it belongs to it.

    Raises:
        InputError: The session is done, the bag was added already, or it was recorded
            for another robot or another route.

    """
    last = index.batches[-1]
    for batch in index.batches:
        recording = batch.recording
        if recording is not None and recording.bag_sha256 == digest and (batch is not last or index.ended):
            raise InputError(
                f"{recorded.path}: this bag was already added (batch {batch.number}, sha256 {digest[:12]})"
            )
    if index.ended:
        verdict = "done" if index.done else "at its floor (no new low above the target)"
        where = f"{last.folder}/{CALIBRATION_FOLDER}"
        raise InputError(f"{folder}: the session is {verdict}: the calibration is in {where}")
    if last.recording is not None and last.recording.bag_sha256 != digest:
        raise InputError(
            f"{folder}: batch {last.number} was added from {last.recording.bag} and its next batch is not planned "
            "yet: rerun posegen session add with that bag to finish"
        )
    made = recorded.provenance or {}
    model = made.get("robot_model_sha256")
    if model and model != index.provenance.get("robot_model_sha256"):
        raise InputError(f"{recorded.path}: recorded by another robot model (sha256 {str(model)[:12]})")
    route_sha = (made.get("simulation") or {}).get("route_sha256")
    if route_sha and route_sha != last.files.get(f"{last.folder}/{ROUTE_FILE}"):
        raise InputError(
            f"{recorded.path}: a recording of another route, not of batch {last.number}'s "
            f"({last.folder}/{ROUTE_FILE}; another session's bag?)"
        )
    return last


def add_bag(session: str, bag: str, backend: Backend, new_table: bool = False, report: Report | None = None) -> Added:
    """Measure a recorded batch, calibrate on every contact so far, and plan the next batch unless done.

    A journal: each step writes its files, then the index (under the session's lock). The
    calibration folder lands whole, with ``report`` written into it before it is swapped
    in. Killed anywhere, the session is the one before a step, and the same command
    resumes it; everything it reads (the index, the files it vouches for, the bag) is
    checked before any step writes.

    Args:
        session: Session folder.
        bag: The rosbag2 the robot recorded while playing the last batch.
        backend: Where routing, checking and cross-validation run.
        new_table: The table was moved (or is another one): the bag's contacts get their own plane.
        report: Writes the calibration's report into its staging folder, given that folder
            and the calibration's destination (``posegen session add``: ``report.html``).

    Raises:
        PosegenError: Not a session, a file edited by hand, a bag of another session,
            robot or route, a bag added twice, or a bag without contacts.

    """
    folder = Path(session)
    open_session(folder)  # not a session: said before anything else (and before the lock)
    recorded = RecordedBag(bag)
    digest = recorded.sha256()
    with claim_output(folder, OutputKind.FOLDER):
        return add_recorded(folder, recorded, digest, backend, new_table, report)


def add_recorded(
    folder: Path, recorded: RecordedBag, digest: str, backend: Backend, new_table: bool, report: Report | None
) -> Added:
    """:func:`add_bag`'s steps, by a caller that holds the session's lock."""
    index = open_session(folder)  # under the lock: another add may have just finished
    batch = _check_bag(index, folder, recorded, digest)
    if batch.state is BatchState.PLANNED:
        batch = _record(folder, index, batch, str(recorded.path), digest, new_table)
        index = index.with_batch(batch)
        write_index(folder, index)
    if batch.state is BatchState.RECORDED:
        batch = _assess(folder, index, batch, backend, report)
        index = index.with_batch(batch)
        write_index(folder, index)
    if index.ended:
        return Added(batch, None, index)
    next_batch = _plan_next(folder, index, batch, backend)
    index = index.with_batch(next_batch)
    write_index(folder, index)
    return Added(batch, next_batch, index)


def _record(folder: Path, index: SessionIndex, batch: Batch, bag: str, digest: str, new_table: bool) -> Batch:
    """Measure the bag against the batch's route (PLANNED -> RECORDED)."""
    tables = sorted({b.recording.table for b in index.batches if b.recording is not None})
    table = table_name(len(tables) + 1) if new_table and tables else index.table
    measurements = folder / batch.folder / MEASUREMENTS_FILE
    measured = measure_bag(
        bag,
        str(measurements),
        config_path=str(folder / CONFIG_FILE),
        route_path=str(folder / batch.folder / ROUTE_FILE),
        session=table,
        joint_topic=index.settings.joint_topic,
        use_wrench=True,
    )
    recording = Recording(
        bag=str(Path(bag).resolve()),
        bag_sha256=digest,
        table=table,
        contacts=len(measured.windows),
        duration_s=round(measured.duration_s, 3),
        missing=missing_rows(batch.pool_rows, [w.label for w in measured.windows]),
    )
    files = {**batch.files, f"{batch.folder}/{MEASUREMENTS_FILE}": sha256_of(measurements)}
    return replace(batch, recording=recording, files=files)


def _measurement_files(folder: Path, index: SessionIndex) -> list[str]:
    return [str(folder / b.folder / MEASUREMENTS_FILE) for b in index.batches if b.recording is not None]


def _assess(folder: Path, index: SessionIndex, batch: Batch, backend: Backend, report: Report | None) -> Batch:
    """Calibrate on every contact so far; the deliverable's predicted error against the target (-> ASSESSED)."""
    settings = index.settings
    calibration = Settings(
        prior_scale=settings.prior_scale,
        candidates=settings.candidates,
        fold_seeds=settings.fold_seeds,
        seed=settings.seed,
    )
    output = folder / batch.folder / CALIBRATION_FOLDER
    given = _measurement_files(folder, index)
    finish = None if report is None else (lambda staging: report(staging, output))
    try:
        calibrated = calibrate_files(
            given, [], str(output), calibration, str(folder / CONFIG_FILE), backend=backend, finish=finish
        )
    except InputError as exc:  # too few usable contacts yet (a batch played in part): plan the missing ones
        contacts = sum(b.recording.contacts for b in index.batches if b.recording is not None)
        return replace(batch, assessment=Assessment(contacts, "", "", {}, False, error=str(exc)))
    deliverables = calibrated.summary.deliverables
    kind = DeliverableKind(settings.deliverable.value)
    entry = deliverables.get(kind) or deliverables[DeliverableKind.URDF]
    predicted = {c: e.mean_abs.z_mm for c, e in sorted(entry.predicted_error.items())}
    done = all(v <= settings.target_mm for v in predicted.values())
    assessment = Assessment(calibrated.training_contacts, entry.kind.value, entry.candidate, predicted, done)
    made = {str(p.relative_to(folder)): sha256_of(p) for p in sorted(output.rglob("*")) if p.is_file()}
    return replace(batch, assessment=assessment, files={**batch.files, **made})  # the whole folder, its report too


def _plan_next(folder: Path, index: SessionIndex, batch: Batch, backend: Backend) -> Batch:
    """The next batch: the missing postures, then ``select --given`` on the weakest chain (-> PLANNED)."""
    assert batch.assessment is not None and batch.recording is not None
    number = batch.number + 1
    calibrated = not batch.assessment.error
    predicted = batch.assessment.predicted_z_mm
    weakest = max(sorted(predicted), key=lambda c: predicted[c]) if predicted else None
    missing = batch.recording.missing
    sources = BatchSources(
        given=tuple(_measurement_files(folder, index)),
        calibration=str(folder / batch.folder / CALIBRATION_FOLDER / "calibration.yaml") if calibrated else None,
        weakest=weakest,
        missing=missing,
        follow=calibrated or not missing,
        planned=tuple(row for b in index.batches for row in b.pool_rows),
    )
    pool = load_pool(index.pool)
    sub = folder / batch_folder(number)
    sub.mkdir(exist_ok=True)
    select_next(index.pool, pool, sub, sources, index.settings)
    return route_batch(folder, number, index.pool, index.settings, backend, sources.planned)
