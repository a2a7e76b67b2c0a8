"""A batch: its postures chosen, routed from where the robot stands, checked, and exported as a rosbag2 to play.

The first batch is the select stage's exact-k design of (1 + margin) x the fewest
postures that identify every base parameter of the pool's chains (more when that
design does not identify them all); the next ones are ``select --given`` on the
weakest chain, after the postures of the previous batch that the robot did not record,
among the postures the session has not planned yet (none is measured twice).
The first batch starts at the start posture; each next one where the robot stands, the
end of the previous batch's route (the start posture again when routes return to it,
the config's ``route.return_to_start``; above its last contact otherwise).
Every file goes through the stages' own functions (the same files their commands write).
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from posegen.errors import InfeasibleError, InputError
from posegen.io import Pool, read_route
from posegen.model import build_design
from posegen.parallel import Backend
from posegen.robot import scene_for
from posegen.route import check_route_file, export_route_bag, route_postures_file, start_posture
from posegen.select import (
    ChosenPosture,
    DesignFigures,
    Selection,
    SelectionMethod,
    SelectionSettings,
    SessionFigures,
    chosen_from_pool,
    follow_up_pool_file,
    iroc,
    select_pool_file,
    write_selection,
)
from posegen.session.index import ROUTE_BAG, Batch, SessionSettings, batch_folder, sha256_of

SELECTION_FILE = "selection.yaml"
FOLLOW_UP_FILE = "followup.yaml"
ROUTE_FILE = "route.yaml"
MEASUREMENTS_FILE = "measurements.yaml"
CALIBRATION_FOLDER = "calibration"
_POOL_ROW = re.compile(r"\(pool (\d+)\)")


@dataclass(frozen=True)
class BatchSources:
    """Where a batch's postures come from."""

    given: tuple[str, ...] = ()  # measurement files so far (none: the first batch)
    calibration: str | None = None  # their calibration.yaml (none: no follow-up, only the missing postures)
    weakest: str | None = None  # the chain to improve
    missing: tuple[int, ...] = ()  # pool rows the robot did not record: planned again, first
    follow: bool = True  # add ``select --given`` postures (False: only the missing ones, too few to calibrate)
    planned: tuple[int, ...] = ()  # pool rows of every batch so far: never chosen again (the missing come first)


def first_batch_size(pool: Pool, margin: float) -> tuple[int, int]:
    """Postures of the first batch, and the base parameters of the pool's chains.

    (1 + margin) x the fewest postures with as many measured rows as base parameters, at most the pool.
    """
    scene = scene_for(pool.provenance, None)
    design, _ = build_design(scene, pool.joints(), [p.chain for p in pool.postures])
    fewest = design.fewest(iroc(design).ranking)
    return min(len(pool.postures), math.ceil(fewest * (1.0 + margin))), design.n_params


def select_first(pool_path: str, pool: Pool, output: Path, settings: SessionSettings) -> Selection[DesignFigures]:
    """The first batch's selection: exact k, grown until it identifies every base parameter.

    Raises:
        InfeasibleError: The whole pool does not identify them.

    """
    k, base = first_batch_size(pool, settings.margin)
    while True:
        selection = select_pool_file(pool_path, str(output), SelectionSettings(k=k, seed=settings.seed))
        if selection.figures.rank >= base:
            return selection
        if k >= len(pool.postures):
            raise InfeasibleError(f"{pool_path}: the whole pool identifies only {selection.figures.rank} of {base}")
        k = min(len(pool.postures), k + max(1, k // 10))


def select_next(pool_path: str, pool: Pool, folder: Path, sources: BatchSources, settings: SessionSettings) -> None:
    """The next batch's selection: the missing postures first, then ``select --given`` on the weakest chain.

    The follow-up chooses among the pool postures no batch of the session holds yet (up to
    ``batch_postures``, fewer when fewer are left).

    Raises:
        InfeasibleError: Nothing left to plan: no missing posture, and every pool posture planned already.

    """
    followed: tuple[ChosenPosture, ...] = ()
    provenance = {**pool.provenance, "pool": pool_path, "pool_sha256": sha256_of(Path(pool_path))}
    excluded = sorted(set(sources.planned) | set(sources.missing))
    k = min(settings.batch_postures, len(pool.postures) - len(excluded))
    if k <= 0 and not sources.missing:
        raise InfeasibleError(
            f"{pool_path}: every posture of the pool is in the session already and the target is not met: "
            "generate a larger pool (posegen pool) and start a new session"
        )
    following = None
    if sources.follow and k > 0:
        selection = follow_up_pool_file(
            pool_path,
            str(folder / FOLLOW_UP_FILE),
            list(sources.given),
            sources.calibration,
            k,
            weakest=sources.weakest,
            exclude=excluded,
        )
        followed, provenance, following = selection.postures, selection.provenance, selection.figures
    again = tuple(chosen_from_pool(pool, row, 0, 0.0) for row in sources.missing)
    write_selection(
        folder / SELECTION_FILE,
        Selection(
            provenance,
            SelectionMethod.SESSION,
            pool.joint_names,
            SessionFigures(sources.missing, following),
            (*again, *followed),
        ),
    )


STANDING_TOLERANCE_RAD = 1e-6  # a route's end this close to the start posture is the start posture


def standing_posture(route: Path) -> list[float] | None:
    """Where the robot stands once it has played a route: its last point (rad, in the robot's joint order).

    None when that is the start posture (the reference posture the route stage starts from by default).
    """
    read = read_route(route)
    scene = scene_for(read.provenance, None)
    end = read.positions[-1, read.joint_columns(scene.joint_names, str(route))]
    reference = start_posture(scene)
    if reference is not None and np.abs(end - reference).max() < STANDING_TOLERANCE_RAD:
        return None
    return [float(v) for v in end]


def route_batch(
    session: Path, number: int, pool_path: str, settings: SessionSettings, backend: Backend, held: Sequence[int] = ()
) -> Batch:
    """Route the batch's selection from where the robot stands, check it on the meshes, export its rosbag2.

    ``held``: the pool rows of the session's earlier batches, which a repair never routes again.

    Raises:
        InfeasibleError: The route fails its check (nothing is exported).

    """
    folder = session / batch_folder(number)
    route = folder / ROUTE_FILE
    standing = standing_posture(session / batch_folder(number - 1) / ROUTE_FILE) if number > 1 else None
    routed = route_postures_file(
        str(folder / SELECTION_FILE),
        str(route),
        settings.seed,
        None,
        workers=backend,
        pool_path=pool_path,
        from_posture=standing,
        held_rows=held,
    )
    verdict = check_route_file(str(route), None, workers=backend)
    if not verdict.ok:
        bad = next(w for w in verdict.worst if w.checked and w.violations)
        raise InfeasibleError(f"{route}: the route fails its check ({bad.invariant.value}: {bad.detail})")
    export_route_bag(str(route), str(folder / ROUTE_BAG), settings.trajectory_topic, settings.segments_topic)
    files = [
        folder / SELECTION_FILE,
        *routed.written,
        *sorted(p for p in (folder / ROUTE_BAG).iterdir() if p.is_file()),
    ]
    return Batch(
        number=number,
        pool_rows=route_pool_rows(str(route)),
        planned_s=round(routed.summary.duration_s, 3),  # as the index records it
        files={str(p.relative_to(session)): sha256_of(p) for p in files},
    )


def route_pool_rows(route: str) -> tuple[int, ...]:
    """The pool rows a route holds a contact at, in its order."""
    rows = read_route(route).hold_pool_rows()
    if None in rows:
        raise InputError(f"{route}: a hold names no pool row")
    return tuple(int(r) for r in rows if r is not None)


def missing_rows(planned: Sequence[int], labels: Sequence[str]) -> tuple[int, ...]:
    """The planned pool rows that no measured contact's label names (a batch played in part), in planned order.

    Args:
        planned: Pool rows of the batch's route, in its order.
        labels: The measured contacts' labels (their route contact's, "... (pool N)").

    """
    found = {int(m.group(1)) for label in labels if (m := _POOL_ROW.search(label))}
    return tuple(row for row in planned if row not in found)
