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
import hashlib
import itertools
import json
import logging
import multiprocessing
import os
from collections.abc import Callable, Generator
from pathlib import Path
from typing import Any

from posegen import __version__
from posegen.artefact import provenance
from posegen.config import Config
from posegen.errors import InfeasibleError, InputError
from posegen.pool import Pool, rejection_counts
from posegen.sampler import Posture, PostureSampler, Rejection
from posegen.scene import Scene

LOG = logging.getLogger(__name__)

PROBE_SAMPLES = 256  # no feasible posture among the first this many: the scene is infeasible
MAX_SAMPLES_PER_POSTURE = 200  # give up when the acceptance rate falls below 1/this

Outcome = Posture | Rejection
ProgressCallback = Callable[[int, int], None]  # (accepted so far, attempted so far)

_WORKER: dict[str, PostureSampler] = {}


def _init_worker(config: Config, seed: int) -> None:
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    _WORKER["sampler"] = PostureSampler(Scene(config), seed)


def _run_chunk(indices: range) -> list[Outcome]:
    sampler = _WORKER["sampler"]
    return [sampler.evaluate(i) for i in indices]


def _encode(outcome: Outcome) -> Any:
    if isinstance(outcome, Rejection):
        return outcome.value
    return {k: getattr(outcome, k) for k in Posture.__dataclass_fields__}


def _decode(raw: Any) -> Outcome:
    if isinstance(raw, str):
        return Rejection(raw)
    return Posture(**{**raw, "joints": tuple(raw["joints"]), "contact_xy_m": tuple(raw["contact_xy_m"])})


class Checkpoint:
    """Append-only record of finished chunks, keyed by what determines the pool."""

    def __init__(self, path: Path, key: str) -> None:
        self.path = path
        self.key = key

    def load(self) -> list[list[Outcome]]:
        """Chunks finished by an earlier run with the same key (none if there was none).

        Raises:
            InputError: A checkpoint of a different run is in the way.

        """
        if not self.path.exists():
            return []
        lines = self.path.read_text().splitlines()
        try:
            header = json.loads(lines[0]) if lines else {}
        except json.JSONDecodeError:
            header = {}
        if header.get("key") != self.key:
            raise InputError(
                f"{self.path} belongs to a different run (config, seed or version); delete it or choose another output"
            )
        chunks = []
        for line in lines[1:]:
            try:
                chunks.append([_decode(r) for r in json.loads(line)])
            except (json.JSONDecodeError, TypeError, ValueError, KeyError):
                break  # a line cut short by the kill: everything after it is redone
        return chunks

    def start(self, chunks: list[list[Outcome]]) -> None:
        """(Re)write the checkpoint with the header and the chunks kept."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with self.path.open("w") as handle:
            handle.write(json.dumps({"key": self.key}) + "\n")
            for chunk in chunks:
                handle.write(json.dumps([_encode(o) for o in chunk]) + "\n")
            handle.flush()
            os.fsync(handle.fileno())

    def append(self, chunk: list[Outcome]) -> None:
        """Record one more finished chunk, durably."""
        with self.path.open("a") as handle:
            handle.write(json.dumps([_encode(o) for o in chunk]) + "\n")
            handle.flush()
            os.fsync(handle.fileno())


def run_key(config: Config, seed: int, model_sha256: str) -> str:
    """Hash of everything the outcome of a sample depends on."""
    text = json.dumps([config.to_dict(), seed, model_sha256, __version__], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


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
    progress: ProgressCallback | None = None,
) -> Pool:
    """Sample until ``n`` feasible postures are found.

    Args:
        config: Scene configuration.
        n: Number of postures wanted (> 0).
        seed: Random seed; the pool depends on (config, seed, n) only.
        workers: Worker processes (1: in this process).
        checkpoint_path: Where finished chunks are recorded for resuming; None: nowhere.
        progress: Called after each chunk with (accepted, attempted).

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
    if progress:
        progress(min(accepted, n), len(outcomes))
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
            if progress:
                progress(min(accepted, n), len(outcomes))
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
