"""The session index: what an experiment holds, as a frozen dataclass with its own reader and writer.

A session folder holds one experiment: ``session.yaml`` (this index) and one subfolder per
batch (``batch_001/``: selection, route, the route's rosbag2 to play, measurements,
calibration). The index is written last, atomically: a file the index does not name is
the leftover of a killed step and is made again; a file it names carries its sha256, so a
file edited by hand is refused (:func:`check_files`).
"""

from __future__ import annotations

import enum
import hashlib
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from posegen.arguments import check_count, check_seed, check_size, check_within
from posegen.errors import InputError
from posegen.io import write_yaml
from posegen.robot import MAX_FOLD_SEEDS, PRIOR_SCALE_RANGE

SESSION_FORMAT = "posegen-session"
SESSION_VERSION = 1
INDEX_FILE = "session.yaml"
MAX_MARGIN = 10.0  # the first batch at most (1 + 10) x the fewest identifying postures
ROUTE_BAG = "route_bag"  # each batch's route as a rosbag2, to play


class Deliverable(str, enum.Enum):
    """Whose predicted error stops the session (the calibration's deliverables)."""

    URDF = "urdf"  # calibrated.urdf alone: what any stack loads
    COMPENSATED = "compensated"  # the URDF with its compliance compensation, when the calibration ships it


class BatchState(str, enum.Enum):
    """How far a batch has gone."""

    PLANNED = "planned"  # selection, route, checked and exported: to play
    RECORDED = "recorded"  # its bag is measured
    ASSESSED = "assessed"  # calibrated on every contact so far


@dataclass(frozen=True)
class SessionSettings:
    """How a session plans and stops; fixed at ``start``, recorded in the index."""

    target_mm: float = 4.0  # stop when every chain's predicted held-out height error (mean abs) is below
    seed: int = 0  # of the routes and of the calibrations' folds
    margin: float = 0.2  # the first batch: (1 + margin) x the fewest postures that identify every base parameter
    batch_postures: int = 10  # postures of each follow-up batch (select --given)
    deliverable: Deliverable = Deliverable.URDF
    candidates: tuple[str, ...] = ()  # the calibrations' candidate models; empty: the config's
    fold_seeds: int | None = None  # repetitions of the calibrations' CV; None: the config's
    prior_scale: float | None = None  # fixed prior scale; None: chosen by CV
    joint_topic: str = "/joint_states"
    trajectory_topic: str = "/joint_trajectory_controller/joint_trajectory"
    segments_topic: str = "/posegen/segments"
    patience: int = 2  # stop at the floor after this many batches without a new low above the target (0: never)


@dataclass(frozen=True)
class Recording:
    """A bag added to a batch, and the contacts measured in it."""

    bag: str  # where it was read
    bag_sha256: str
    table: str  # table session of its contacts
    contacts: int
    duration_s: float  # of its joint states: robot time spent
    missing: tuple[int, ...]  # pool rows of the batch's postures with no contact in the bag


@dataclass(frozen=True)
class Assessment:
    """The calibration on every contact up to a batch, and its verdict."""

    contacts: int  # training contacts read
    deliverable: str  # the deliverable whose CV figure is shown (urdf or compensated)
    candidate: str  # its model
    predicted_z_mm: Mapping[str, float]  # chain -> predicted held-out height error, mean abs (grouped CV)
    done: bool  # every chain below the target
    error: str = ""  # why no calibration could be made yet (too few contacts), else empty


@dataclass(frozen=True)
class Batch:
    """One batch: postures planned, then recorded, then assessed."""

    number: int
    pool_rows: tuple[int, ...]  # the postures planned (pool rows)
    planned_s: float  # robot time of its route
    files: Mapping[str, str]  # file (relative to the session) -> sha256, of what the index vouches for
    recording: Recording | None = None
    assessment: Assessment | None = None

    @property
    def folder(self) -> str:
        """Its subfolder, relative to the session."""
        return batch_folder(self.number)

    @property
    def state(self) -> BatchState:
        """How far it has gone."""
        if self.assessment is not None:
            return BatchState.ASSESSED
        return BatchState.RECORDED if self.recording is not None else BatchState.PLANNED


@dataclass(frozen=True)
class SessionIndex:
    """Everything a session folder holds."""

    provenance: Mapping[str, Any]  # config, robot model hash, seed, posegen version
    pool: str  # the pool file (absolute)
    pool_sha256: str
    settings: SessionSettings
    batches: tuple[Batch, ...] = field(default_factory=tuple)

    @property
    def done(self) -> bool:
        """Whether the last assessment met the target."""
        last = self.batches[-1].assessment if self.batches else None
        return last is not None and last.done

    @property
    def table(self) -> str:
        """The table session of the last recording (the first table when nothing is recorded)."""
        tables = [b.recording.table for b in self.batches if b.recording is not None]
        return tables[-1] if tables else table_name(1)

    @property
    def stalled(self) -> tuple[tuple[str, float, float], ...]:
        """Chains above the target whose predicted error did not fall with the last assessed batch.

        ``(chain, before_mm, after_mm)`` between the last two batches with a calibration
        figure; empty with fewer than two. A chain that stalls above the target may be at
        its deliverable's floor (a URDF cannot hold compliant joints): more contacts of the
        same kind may not bring it there.

        Example:
            >>> [f"{c}: {a:.2f} -> {b:.2f} mm" for c, a, b in index.stalled]

        """
        assessed = [b.assessment for b in self.batches if b.assessment is not None and not b.assessment.error]
        if len(assessed) < 2:
            return ()
        before, after = assessed[-2].predicted_z_mm, assessed[-1].predicted_z_mm
        target = self.settings.target_mm
        return tuple(
            (chain, before[chain], now)
            for chain, now in sorted(after.items())
            if chain in before and now > target and now >= before[chain]
        )

    @property
    def at_floor(self) -> bool:
        """Whether the last ``patience`` batches brought no chain above the target a new lowest predicted error.

        The session's rule for a deliverable that more contacts do not improve (a URDF
        cannot hold compliant joints; its predicted error levels off above a low target):
        with ``patience`` p, it stops when, for every chain still above the target, the
        lowest prediction of the last p assessed batches is not below the lowest of the
        batches before them. No threshold: a new low by any amount continues the session.
        A session that met its target is done, not at its floor.

        Example:
            >>> index.at_floor, index.settings.patience

        """
        patience = self.settings.patience
        assessed = [b.assessment for b in self.batches if b.assessment is not None and not b.assessment.error]
        if self.done or patience < 1 or len(assessed) <= patience:
            return False
        earlier, recent = assessed[:-patience], assessed[-patience:]
        above = [c for c, v in assessed[-1].predicted_z_mm.items() if v > self.settings.target_mm]

        def lowest(assessments: list[Assessment], chain: str) -> float:
            return min((a.predicted_z_mm[chain] for a in assessments if chain in a.predicted_z_mm), default=math.inf)

        return bool(above) and all(lowest(recent, c) >= lowest(earlier, c) for c in above)

    @property
    def ended(self) -> bool:
        """Whether no batch follows: done (the target met) or at the deliverable's floor."""
        return self.done or self.at_floor

    def with_batch(self, batch: Batch) -> SessionIndex:
        """The index with ``batch`` replacing the batch of its number, or appended."""
        kept = tuple(b for b in self.batches if b.number != batch.number)
        return replace(self, batches=tuple(sorted((*kept, batch), key=lambda b: b.number)))


def check_settings(settings: SessionSettings) -> None:
    """Check a session's numbers (at ``start``, and whenever its index is read).

    Raises:
        ArgumentError: A target, margin, seed or count out of range.

    """
    check_size(settings.target_mm, "target_mm", positive=True)
    check_within(settings.margin, "margin", 0.0, MAX_MARGIN)
    check_seed(settings.seed, "seed")
    check_count(settings.batch_postures, "batch_postures")
    if settings.fold_seeds is not None:
        check_count(settings.fold_seeds, "fold_seeds", maximum=MAX_FOLD_SEEDS)
    if settings.prior_scale is not None:
        check_within(settings.prior_scale, "prior_scale", *PRIOR_SCALE_RANGE)
    check_count(settings.patience, "patience", minimum=0)


def batch_folder(number: int) -> str:
    """The subfolder of batch ``number``: ``batch_001``."""
    return f"batch_{number:03d}"


def table_name(number: int) -> str:
    """The name of the ``number``-th table session: ``table_1``."""
    return f"table_{number}"


def sha256_of(path: Path) -> str:
    """The sha256 of a file."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


def index_to_dict(index: SessionIndex) -> dict[str, Any]:
    """Plain data of the index file."""
    settings = dict(index.settings.__dict__)
    settings["deliverable"] = index.settings.deliverable.value
    settings["candidates"] = list(index.settings.candidates)
    batches = []
    for b in index.batches:
        entry: dict[str, Any] = {
            "number": b.number,
            "state": b.state.value,
            "pool_rows": list(b.pool_rows),
            "planned_s": round(b.planned_s, 3),
            "files": dict(sorted(b.files.items())),
            "recording": None
            if b.recording is None
            else {**b.recording.__dict__, "missing": list(b.recording.missing)},
            "assessment": None,
        }
        if b.assessment is not None:
            entry["assessment"] = {**b.assessment.__dict__, "predicted_z_mm": dict(b.assessment.predicted_z_mm)}
        batches.append(entry)
    return {
        "format": SESSION_FORMAT,
        "format_version": SESSION_VERSION,
        "provenance": dict(index.provenance),
        "pool": index.pool,
        "pool_sha256": index.pool_sha256,
        "settings": settings,
        "done": index.done,
        "at_floor": index.at_floor,
        "batches": batches,
    }


def write_index(folder: Path, index: SessionIndex) -> None:
    """Write the index, atomically (the last write of every step)."""
    write_yaml(folder / INDEX_FILE, index_to_dict(index))


def check_files(folder: Path, index: SessionIndex) -> None:
    """Check that every file the index vouches for is there, with its bytes, and every batch's rosbag2 to play.

    Raises:
        InputError: A file missing or changed since the session wrote it, or a batch's
            ``route_bag`` folder gone.

    """
    for batch in index.batches:
        bag = folder / batch.folder / ROUTE_BAG
        if not (bag / "metadata.yaml").is_file():
            raise InputError(f"{bag} is missing: the session's files were moved or deleted by hand")
        for name, digest in batch.files.items():
            path = folder / name
            if not path.is_file():
                raise InputError(f"{path} is missing: the session's files were moved or deleted by hand")
            if sha256_of(path) != digest:
                raise InputError(
                    f"{path} was changed since the session wrote it (sha256 differs): restore it, or start a "
                    "new session"
                )
