"""Generating a pool: samples in chunks, over processes, resumable after a kill.

Chunks of consecutive sample indices are evaluated by worker processes and consumed in
index order; each finished chunk is appended to a checkpoint file beside the output
(``<output>.partial.jsonl``) and flushed to disk. The pool is the first ``n`` accepted
samples in index order, so it depends on (config, seed, n) only. Rerunning the same
command after a kill reads the checkpoint and continues; the pool file itself is
written once, atomically, at the end.
"""

from __future__ import annotations

import concurrent.futures
import itertools
import logging
import multiprocessing
import os
from collections.abc import Generator
from pathlib import Path

from posegen.errors import InfeasibleError
from posegen.io import provenance
from posegen.pool.checkpoint import Checkpoint, Outcome, run_key
from posegen.pool.sampler import PostureSampler, rejection_counts
from posegen.progress import Progress, ProgressCallback, ignore_progress
from posegen.robot import Config, Pool, Posture, Scene

LOG = logging.getLogger(__name__)

PROBE_SAMPLES = 256  # no feasible posture among the first this many: the scene is infeasible
MAX_SAMPLES_PER_POSTURE = 200  # give up when the acceptance rate falls below 1/this

_WORKER: dict[str, PostureSampler] = {}


def _init_worker(config: Config, seed: int) -> None:
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    _WORKER["sampler"] = PostureSampler(Scene(config), seed)


def _run_chunk(indices: range) -> list[Outcome]:
    sampler = _WORKER["sampler"]
    return [sampler.evaluate(i) for i in indices]


def _chunks(config: Config, seed: int, workers: int, first_chunk: int) -> Generator[list[Outcome], None, None]:
    size = config.sampling.chunk_size
    ranges = (range(c * size, (c + 1) * size) for c in itertools.count(first_chunk))
    if workers <= 1:
        _init_worker(config, seed)
        for indices in ranges:
            yield _run_chunk(indices)
        return
    context = multiprocessing.get_context("forkserver")
    with concurrent.futures.ProcessPoolExecutor(
        max_workers=workers, mp_context=context, initializer=_init_worker, initargs=(config, seed)
    ) as executor:
        window: list[concurrent.futures.Future[list[Outcome]]] = []
        try:
            for indices in ranges:
                window.append(executor.submit(_run_chunk, indices))
                if len(window) >= 2 * workers:
                    yield window.pop(0).result()
        finally:
            for future in window:
                future.cancel()


def generate_pool(
    config: Config,
    n: int,
    seed: int,
    workers: int = 1,
    checkpoint_path: Path | None = None,
    progress: ProgressCallback = ignore_progress,
) -> Pool:
    """Sample until ``n`` feasible postures are found.

    Args:
        config: Scene configuration.
        n: Number of postures wanted (> 0).
        seed: Random seed; the pool depends on (config, seed, n) only.
        workers: Worker processes (1: in this process).
        checkpoint_path: Where finished chunks are recorded for resuming; None: nowhere.
        progress: Told after each chunk how many postures are accepted (of ``n``) and
            how many samples were attempted.

    Raises:
        InfeasibleError: No feasible posture in the first samples, or acceptance too low.
        InputError: A checkpoint of a different run is in the way.

    """
    if n <= 0:
        raise InfeasibleError(f"--n must be a positive number of postures, got {n}")
    scene = Scene(config)
    model_sha = scene.files.sha256()
    checkpoint = Checkpoint(checkpoint_path, run_key(config, seed, model_sha)) if checkpoint_path else None
    done = checkpoint.load() if checkpoint else []
    if checkpoint:
        checkpoint.start(done)
    outcomes: list[Outcome] = [o for chunk in done for o in chunk]
    accepted = sum(isinstance(o, Posture) for o in outcomes)
    if done:
        LOG.info("resuming: %d samples already done, %d postures accepted", len(outcomes), accepted)
    progress(Progress(min(accepted, n), n, "posture", attempts=len(outcomes)))
    max_samples = max(PROBE_SAMPLES, MAX_SAMPLES_PER_POSTURE * n)
    chunks = _chunks(config, seed, workers, len(done))
    try:
        while accepted < n:
            if accepted == 0 and len(outcomes) >= PROBE_SAMPLES:
                raise InfeasibleError(
                    f"no feasible posture in the first {len(outcomes)} samples "
                    f"(rejections: {rejection_counts(outcomes)}); is the table within reach?"
                )
            if len(outcomes) >= max_samples:
                raise InfeasibleError(
                    f"only {accepted} feasible postures in {len(outcomes)} samples; "
                    "loosen the margins or move the table"
                )
            chunk = next(chunks)
            if checkpoint:
                checkpoint.append(chunk)
            outcomes.extend(chunk)
            accepted += sum(isinstance(o, Posture) for o in chunk)
            progress(Progress(min(accepted, n), n, "posture", attempts=len(outcomes)))
    finally:
        chunks.close()
    kept: list[Outcome] = []
    count = 0
    for outcome in outcomes:  # the first n accepted samples, and the rejections before the last
        kept.append(outcome)
        count += isinstance(outcome, Posture)
        if count == n:
            break
    postures = tuple(o for o in kept if isinstance(o, Posture))
    return Pool(
        joint_names=scene.joint_names,
        postures=postures,
        provenance=provenance(config.to_dict(), model_sha, seed),
        attempted=len(kept),
        rejected=rejection_counts(kept),
    )
