"""The pool stage's commands, from files to files: ``posegen pool`` and ``posegen check POOL``."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from posegen.arguments import check_count, check_seed
from posegen.errors import InputError, PosegenError
from posegen.io import (
    POOL_FORMAT,
    SELECTION_FORMAT,
    Pool,
    check_apart,
    check_named,
    claim_output,
    postures_of,
    read_yaml,
    write_pool,
)
from posegen.parallel import Backend
from posegen.pool.check import verify_postures
from posegen.pool.generation import generate_pool
from posegen.progress import Progress, ProgressCallback, ignore_progress
from posegen.robot import (
    CollisionChecker,
    Scene,
    Verification,
    check_for_planning,
    geometry_coverage,
    load_config,
    scene_for,
)


def generate_pool_file(
    config_path: str,
    output: str,
    n: int,
    seed: int,
    workers: int | Backend = 1,
    progress: ProgressCallback = ignore_progress,
) -> Pool:
    """Generate (or resume) a pool and write it to ``output``.

    The output is checked and locked before any work (:func:`posegen.io.claim_output`).
    Finished chunks are recorded in ``<output>.partial.jsonl``: rerunning the same
    command after a kill resumes from there. The pool file is written once, atomically,
    and the checkpoint removed after it; a run that fails removes the checkpoint it
    started (one it resumed is kept).

    Raises:
        PosegenError: Bad arguments or config (a reference posture unfit for planning
            included), an output that cannot be written or is being written, an
            infeasible scene, or a checkpoint of another run.

    """
    check_count(n, "n")
    check_seed(seed, "seed")
    if not isinstance(workers, Backend):
        check_count(workers, "workers")
    check_named(output)
    path = Path(output)
    checkpoint = path.with_name(path.name + ".partial.jsonl")
    check_apart([path, checkpoint], [config_path])
    with claim_output(path, beside=(checkpoint,)):
        config = load_config(config_path)
        scene = Scene(config)
        check_for_planning(scene, CollisionChecker(scene, convex=True))
        resuming = checkpoint.exists()
        try:
            pool = generate_pool(config, n, seed, workers, checkpoint, progress)
        except PosegenError:
            if not resuming:
                checkpoint.unlink(missing_ok=True)
            raise
        write_pool(path, pool)
        checkpoint.unlink(missing_ok=True)
    return pool


def check_pool_file(
    path: str,
    config_path: str | None,
    progress: ProgressCallback = ignore_progress,
    workers: int | Backend = 1,
) -> Verification:
    """Re-verify every posture of a pool (or selection) file from scratch, on the robot's meshes.

    Args:
        path: Pool or selection file.
        config_path: Scene config; None: the one saved in the pool.
        progress: Told after each chunk of postures.
        workers: Local worker processes (1: in this process), or the backend to run on.

    Raises:
        PosegenError: Not a pool or selection, no posture, or postures made for another robot model.

    """
    pool = postures_of(read_yaml(path, (POOL_FORMAT, SELECTION_FORMAT)), path)
    if not pool.postures:
        raise InputError(f"{path}: the pool holds no posture: nothing to check")
    scene = scene_for(pool.provenance, config_path)
    scene.check_made_for(pool.provenance, path)
    pool.check_joints(scene.joint_names, path)
    pool.check_names([c.name for c in scene.config.chains], [s.name for s in scene.spots], path)
    progress(Progress(0, len(pool.postures), "posture"))
    result = verify_postures(scene, pool.postures, progress, workers)
    return dataclasses.replace(result, geometry=geometry_coverage(scene))
