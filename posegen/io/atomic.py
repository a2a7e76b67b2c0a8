"""Atomic file writes: an output is either fully there or not changed at all."""

from __future__ import annotations

import contextlib
import glob
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path


def _temporary_prefix(path: Path) -> str:
    return f".{path.name}."


def leftover_temporaries(path: str | Path) -> list[Path]:
    """Temporary files of writes to ``path`` that a killed process left beside it."""
    path = Path(path)
    return sorted(path.parent.glob(glob.escape(_temporary_prefix(path)) + "*.tmp*"))


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """A temporary path beside ``path`` to write to; renamed onto ``path`` when the block succeeds.

    For writers that want a file name (``savefig``, a zip writer). If the block raises,
    or the process dies in it, ``path`` is unchanged and the temporary file is removed
    (or, after a kill, left as a hidden ``.<name>.*.tmp*`` beside it, which the next
    writer of ``path`` removes: :func:`leftover_temporaries`).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(prefix=_temporary_prefix(path), suffix=".tmp" + path.suffix, dir=path.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        with tmp.open("rb+") as handle:
            os.fsync(handle.fileno())
        os.chmod(tmp, 0o644)  # mkstemp creates 0600; artefacts are ordinary files
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_atomic(path: str | Path, content: str | bytes) -> None:
    """Write a file (text, or bytes) so that it is either fully there or not changed at all."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(content.encode() if isinstance(content, str) else content)
