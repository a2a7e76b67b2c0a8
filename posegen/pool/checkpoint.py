"""The checkpoint of a pool run: finished chunks of samples, appended as they come.

One JSON line per finished chunk, after a header with the key of the run (a hash of the
config, seed, robot model and posegen version), flushed to disk each time: a killed run
is resumed from it, and a checkpoint of another run is never mixed in.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

from posegen import __version__
from posegen.errors import InputError
from posegen.io import Posture, posture_from_dict, read_text_file
from posegen.pool.sampler import Rejection
from posegen.robot import Config

Outcome = Posture | Rejection


def _encode(outcome: Outcome) -> Any:
    if isinstance(outcome, Rejection):
        return outcome.value
    return {k: getattr(outcome, k) for k in Posture.__dataclass_fields__}


def _decode(raw: Any, n_joints: int) -> Outcome:
    if isinstance(raw, str):
        return Rejection(raw)
    return posture_from_dict(raw, n_joints, "checkpoint")


class Checkpoint:
    """Append-only record of finished chunks, keyed by what determines the pool."""

    def __init__(self, path: Path, key: str, n_joints: int) -> None:
        self.path = path
        self.key = key
        self.n_joints = n_joints  # joints per posture

    def load(self) -> list[list[Outcome]]:
        """Chunks finished by an earlier run with the same key (none if there was none).

        Raises:
            InputError: A checkpoint of a different run is in the way.

        """
        if not self.path.exists():
            return []
        lines = read_text_file(self.path, InputError).splitlines()
        try:
            header = json.loads(lines[0]) if lines else {}
        except (json.JSONDecodeError, RecursionError):
            header = {}
        if not isinstance(header, dict) or header.get("key") != self.key:
            raise InputError(
                f"{self.path} belongs to a different run (config, seed or version); delete it or choose another output"
            )
        chunks = []
        for line in lines[1:]:
            try:
                chunks.append([_decode(r, self.n_joints) for r in json.loads(line)])
            except (json.JSONDecodeError, TypeError, ValueError, KeyError, InputError):
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
