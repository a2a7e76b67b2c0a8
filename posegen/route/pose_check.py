"""The robot's pose at every route point: second sole, CoM, collisions on the meshes.

Kinematics by pinocchio from the stored joint angles alone (the floating base re-solved
from the anchor sole); collisions by coal on the robot's original meshes, not the hulls
the planner used, with the configured margin. Fingertips may touch the table only in
contact segments, where the margin shrinks by the commanded overshoot; in free segments
the table's pairs keep ``margins.table_clearance_m`` when the config sets it. Collisions are
the costly part (about 1 ms a point): points are checked in chunks over worker
processes, each loading the meshes once; the pair and its distance are measured only
at the points found colliding.

Angles are stored as float32 (see :mod:`posegen.io.route_file`): the CoM and the
collision distances get 1e-6 m of slack for that rounding (it moves a body by ~1e-7 m).
"""

from __future__ import annotations

import enum
import functools
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from posegen.io import Segment, SegmentType
from posegen.parallel import Backend, Job, as_backend, job_name
from posegen.progress import Progress, ProgressCallback
from posegen.robot import (
    SOLE_ANGLE_TOL_RAD,
    SOLE_POSITION_TOL_M,
    CollisionChecker,
    Config,
    FloatArray,
    Scene,
    Worst,
    worst_case,
)

STORAGE_TOL_M = 1e-6  # slack on the CoM margin and collision distances for float32 angles
CHUNK = 250  # points per collision job
Chunk = tuple[FloatArray, list[str | None], FloatArray, FloatArray]  # (k, nj) rad, chains, margins (k,) m, table's (k,)


class PoseInvariant(str, enum.Enum):
    """What the robot's pose at every route point must satisfy."""

    SOLE = "sole"
    COM = "com"
    COLLISION = "collision"


def _meshes(config: Config) -> tuple[Scene, CollisionChecker]:
    """A worker's state: the scene and a collision checker on the original meshes."""
    scene = Scene(config)
    return scene, CollisionChecker(scene, convex=False)


def collision_job(scene: Scene) -> Job[tuple[Scene, CollisionChecker], Chunk, list[tuple[float, str]]]:
    """The check's costly work: chunks of route points, each checked on a worker's meshes."""
    return Job(
        name=job_name("route-check", scene.config.to_dict(), scene.files.sha256()),
        setup=functools.partial(_meshes, scene.config),
        run=_collisions,
    )


def _collisions(state: tuple[Scene, CollisionChecker], job: Chunk) -> list[tuple[float, str]]:
    """(excess over the margin, detail) of each point of a chunk; excess <= 0 when clear.

    A point's table margin (nan: none) applies to the pairs of the robot and the table.
    """
    scene, meshes = state
    out = []
    for joints, chain, margin, table in zip(*job, strict=True):
        q = scene.configuration(joints)
        table_margin = None if np.isnan(table) else float(table) - STORAGE_TOL_M
        if not meshes.collides(q, chain, margin - STORAGE_TOL_M, table_margin):
            out.append((-margin, ""))
            continue
        hits = meshes.colliding_pairs(q, chain, margin - STORAGE_TOL_M, table_margin)
        if not hits:  # the fast check's warm start saw it within 1e-15 m of the margin: take the exact answer
            out.append((-margin, ""))
            continue
        worst = max(hits, key=lambda hit: hit.excess_m)  # each pair's own margin: the checker's rule
        out.append((worst.excess_m + STORAGE_TOL_M, f"{worst.pair[0]} - {worst.pair[1]} at {worst.distance_m:.4f} m"))
    return out


def check_poses(
    scene: Scene,
    segments: Sequence[Segment],
    times: FloatArray,
    positions: FloatArray,
    finite: np.ndarray,
    workers: int | Backend,
    progress: ProgressCallback,
) -> list[Worst]:
    """Sole, CoM and collision at every point with finite angles.

    Args:
        scene: The scene.
        segments: The route's segment table.
        times: (m,) s.
        positions: (m, nj) rad.
        finite: (m,) whether a point's angles are all finite (the others are skipped;
            every point of a route the reader accepted is).
        workers: Local processes for the collision checks, or the backend to run them on.
        progress: Told as points are checked for collisions.

    """
    m = len(times)
    chains, margins, tables = _margins(scene, segments, m)
    clearance = scene.margins.table_clearance_m
    sole, com = np.full(m, -np.inf), np.full(m, -np.inf)
    sole_detail: dict[int, str] = {}
    com_value = np.full(m, np.nan)
    data = scene.model.createData()
    second = scene.second_sole
    target = pin.SE3(scene.sole_poses[second])
    frame = scene.frame_id(second)
    for k in np.flatnonzero(finite):
        q = scene.configuration(positions[k])
        pin.framesForwardKinematics(scene.model, data, q)
        error = target.actInv(data.oMf[frame])
        position_error = float(np.linalg.norm(error.translation))
        angle_error = float(np.linalg.norm(pin.log3(error.rotation)))
        sole[k] = max(position_error - SOLE_POSITION_TOL_M, angle_error - SOLE_ANGLE_TOL_RAD)
        sole_detail[int(k)] = f"{position_error:.2e} m, {angle_error:.2e} rad"
        com_value[k] = scene.com_margin(q, data)
        com[k] = scene.margins.com_m - STORAGE_TOL_M - com_value[k]
    collision, collision_detail = _check_collisions(
        scene, positions, chains, (margins, tables), finite, workers, progress
    )

    def at(k: int) -> str:
        return f"point {k} (t {times[k]:.4f} s)"

    def table_clause(k: int) -> str:
        return "" if np.isnan(tables[k]) else f", {tables[k]} m from the table"

    return [
        worst_case(
            PoseInvariant.SOLE,
            sole,
            lambda k: (
                f"{at(k)} second sole off its pose by {sole_detail[k]}; tolerance "
                f"{SOLE_POSITION_TOL_M} m, {SOLE_ANGLE_TOL_RAD} rad"
            ),
            "second sole on its pose",
        ),
        worst_case(
            PoseInvariant.COM,
            com,
            lambda k: f"{at(k)} CoM {com_value[k]:.4f} m inside the support polygon; margin {scene.margins.com_m} m",
            f"CoM inside the support polygon by {scene.margins.com_m} m",
        ),
        worst_case(
            PoseInvariant.COLLISION,
            collision,
            lambda k: f"{at(k)} {collision_detail[k]}; margin {margins[k]} m{table_clause(k)} (meshes)",
            "no pair closer than its margin (meshes)"
            + (f", free motions {clearance} m above the table" if clearance > 0 else ""),
        ),
    ]


def _margins(scene: Scene, segments: Sequence[Segment], m: int) -> tuple[list[str | None], FloatArray, FloatArray]:
    """Each point's chain at the table (or None), collision margin (m,) m and table margin (m,) m (nan: none)."""
    chains: list[str | None] = [None] * m
    margins = np.full(m, scene.margins.collision_m)
    tables = np.full(m, np.nan)  # the free points' table margin, if the config keeps them clear of it
    clearance = scene.margins.table_clearance_m
    for seg in segments:
        if seg.type.in_contact:
            for k in range(seg.first_point, seg.last_point + 1):
                chains[k] = seg.chain
                margins[k] = scene.contact_collision_margin_m
        elif seg.type is SegmentType.FREE and clearance > 0:
            tables[seg.first_point : seg.last_point + 1] = clearance
    return chains, margins, tables


def _check_collisions(
    scene: Scene,
    positions: FloatArray,
    chains: list[str | None],
    margins: tuple[FloatArray, FloatArray],
    finite: np.ndarray,
    workers: int | Backend,
    progress: ProgressCallback,
) -> tuple[FloatArray, dict[int, str]]:
    """Each point's excess over its margin (m; -inf: not checked) and the detail of those colliding."""
    points = np.flatnonzero(finite)
    jobs = [points[i : i + CHUNK] for i in range(0, len(points), CHUNK)]
    excess = np.full(len(positions), -np.inf)
    detail: dict[int, str] = {}
    backend = as_backend(workers)
    requests = ((positions[idx], [chains[k] for k in idx], margins[0][idx], margins[1][idx]) for idx in jobs)
    done = 0
    for idx, results in zip(jobs, backend.map(collision_job(scene), requests), strict=True):
        for k, (value, text) in zip(idx, results, strict=True):
            excess[k] = value
            if text:
                detail[int(k)] = text
        done += len(idx)
        progress(Progress(done, len(points), "point"))
    return excess, detail
