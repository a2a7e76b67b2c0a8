"""Generating a pool: samples in chunks, over processes or a cluster, resumable after a kill.

Chunks of consecutive sample indices are evaluated by workers (local processes or Dask
workers, :mod:`posegen.parallel`) and consumed in index order; each finished chunk is
appended to a checkpoint file beside the output (``<output>.partial.jsonl``) and flushed
to disk. The pool is the first ``n`` accepted
samples in index order, so it depends on (config, seed, n) only. Rerunning the same
command after a kill reads the checkpoint and continues; the pool file itself is
written once, atomically, at the end.
"""

from __future__ import annotations

import functools
import itertools
import logging
from collections.abc import Iterator
from pathlib import Path

from posegen.arguments import check_seed
from posegen.errors import BackendError, InfeasibleError
from posegen.io import Pool, Posture, provenance
from posegen.parallel import Backend, Job, as_backend
from posegen.pool.checkpoint import Checkpoint, Outcome, run_key
from posegen.pool.sampler import PostureSampler, rejection_counts
from posegen.progress import Progress, ProgressCallback, ignore_progress
from posegen.robot import Config, Scene, check_for_planning

LOG = logging.getLogger(__name__)

PROBE_SAMPLES = 256  # no feasible posture among the first this many: the scene is infeasible
MAX_SAMPLES_PER_POSTURE = 200  # give up when the acceptance rate falls below 1/this


def _sampler(config: Config, seed: int, model_sha256: str) -> PostureSampler:
    scene = Scene(config)
    found = scene.files.sha256()
    if found != model_sha256:  # a worker on another machine with another robot description
        raise BackendError(
            f"a worker's robot model differs from this one (sha256 {found[:12]} vs {model_sha256[:12]}); "
            "install the same robot description on every worker"
        )
    return PostureSampler(scene, seed)


def _evaluate(sampler: PostureSampler, indices: range) -> list[Outcome]:
    return [sampler.evaluate(i) for i in indices]


def sampling_job(config: Config, seed: int, model_sha256: str) -> Job[PostureSampler, range, list[Outcome]]:
    """The pool's work: chunks of sample indices, each turned into outcomes by a worker's sampler."""
    return Job(
        name=f"pool-{run_key(config, seed, model_sha256)[:16]}",
        setup=functools.partial(_sampler, config, seed, model_sha256),
        run=_evaluate,
    )


def _sample_until(
    n: int,
    outcomes: list[Outcome],
    chunks: Iterator[list[Outcome]],
    checkpoint: Checkpoint | None,
    progress: ProgressCallback,
) -> None:
    """Take chunks of outcomes (appended to ``outcomes``) until ``n`` postures are accepted.

    Raises:
        InfeasibleError: No feasible posture in the first samples, or acceptance too low.

    """
    accepted = sum(isinstance(o, Posture) for o in outcomes)
    max_samples = max(PROBE_SAMPLES, MAX_SAMPLES_PER_POSTURE * n)
    while accepted < n:
        if accepted == 0 and len(outcomes) >= PROBE_SAMPLES:
            raise InfeasibleError(
                f"no feasible posture in the first {len(outcomes)} samples "
                f"(rejections: {rejection_counts(outcomes)}); is the table (table.top_center_m) within the "
                "arms' reach, and can a hand press route.contact_force_n within margins.effort_ratio of the "
                "effort limits?"
            )
        if len(outcomes) >= max_samples:
            raise InfeasibleError(
                f"only {accepted} feasible postures in {len(outcomes)} samples (rejections: "
                f"{rejection_counts(outcomes)}); loosen the margins or move the table"
            )
        chunk = next(chunks)
        if checkpoint:
            checkpoint.append(chunk)
        outcomes.extend(chunk)
        accepted += sum(isinstance(o, Posture) for o in chunk)
        progress(Progress(min(accepted, n), n, "posture", attempts=len(outcomes)))


def _first_accepted(outcomes: list[Outcome], n: int) -> list[Outcome]:
    """The outcomes up to the ``n``-th accepted posture (the rejections before it kept)."""
    kept: list[Outcome] = []
    count = 0
    for outcome in outcomes:
        kept.append(outcome)
        count += isinstance(outcome, Posture)
        if count == n:
            break
    return kept


def generate_pool(
    config: Config,
    n: int,
    seed: int,
    workers: int | Backend = 1,
    checkpoint_path: Path | None = None,
    progress: ProgressCallback = ignore_progress,
) -> Pool:
    """Sample until ``n`` feasible postures are found.

    Args:
        config: Scene configuration.
        n: Number of postures wanted (> 0).
        seed: Random seed; the pool depends on (config, seed, n) only.
        workers: Local worker processes (1: in this process), or the backend to run on.
        checkpoint_path: Where finished chunks are recorded for resuming; None: nowhere.
        progress: Told after each chunk how many postures are accepted (of ``n``) and
            how many samples were attempted.

    Raises:
        ConfigError: The reference posture or the table fails a planning check.
        InfeasibleError: No feasible posture in the first samples, or acceptance too low.
        InputError: A checkpoint of a different run is in the way.
        BackendError: A worker cannot run the job (another version or robot model).

    """
    if n <= 0:
        raise InfeasibleError(f"n must be a positive number of postures, got {n}", parameter="n")
    check_seed(seed)
    scene = Scene(config)
    check_for_planning(scene)  # soles, balance and reach of the reference posture: cheap, before any sample
    model_sha = scene.files.sha256()
    key = run_key(config, seed, model_sha)
    checkpoint = Checkpoint(checkpoint_path, key, len(scene.joint_names)) if checkpoint_path else None
    done = checkpoint.load() if checkpoint else []
    if checkpoint:
        checkpoint.start(done)
    outcomes: list[Outcome] = [o for chunk in done for o in chunk]
    accepted = sum(isinstance(o, Posture) for o in outcomes)
    if done:
        LOG.info("resuming: %d samples already done, %d postures accepted", len(outcomes), accepted)
    progress(Progress(min(accepted, n), n, "posture", attempts=len(outcomes)))
    backend = as_backend(workers)
    size = config.sampling.chunk_size
    ranges = (range(c * size, (c + 1) * size) for c in itertools.count(len(done)))
    chunks = backend.map(sampling_job(config, seed, model_sha), ranges)
    try:
        _sample_until(n, outcomes, chunks, checkpoint, progress)
    finally:
        chunks.close()
    kept = _first_accepted(outcomes, n)
    postures = tuple(o for o in kept if isinstance(o, Posture))
    return Pool(
        joint_names=scene.joint_names,
        postures=postures,
        provenance=provenance(config.to_dict(), model_sha, seed),
        attempted=len(kept),
        rejected=rejection_counts(kept),
    )
