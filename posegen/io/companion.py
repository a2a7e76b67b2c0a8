"""Files that go with a header and are replaced with it: named by the header's content hash.

A companion is a file written beside a header (a YAML artefact) that has no meaning
without it: a simulation's true parameters beside its measurements, a route's points as
CSV. It is named ``<header name>.<sha256 prefix of the header's bytes><suffix>``
(``m.yaml.3fa2b1c4d5e6.truth.yaml``), so the header on disk always finds its own
companion, and a new one never overwrites the old header's: the companions land first,
the header next (one rename: the moment the artefact changes), then the companions no
header names any more are removed. A kill at any point leaves the old header with its
companions or the new one with its own, plus at most companions no header names, which
the next write of that header removes. The header's bytes do not change.
"""

from __future__ import annotations

import hashlib
import re
from collections.abc import Mapping
from pathlib import Path

from posegen.io.atomic import crash_point, write_atomic

NAME_DIGITS = 12  # hex digits of the header's sha256 in a companion's name


def companion_path(path: str | Path, header: bytes, suffix: str) -> Path:
    """Where the companion ``suffix`` of the header at ``path`` holding ``header`` goes."""
    path = Path(path)
    digest = hashlib.sha256(header).hexdigest()[:NAME_DIGITS]
    return path.with_name(f"{path.name}.{digest}{suffix}")


def companions_of(path: str | Path, suffix: str) -> list[Path]:
    """The companions ``suffix`` named after the header at ``path`` that exist beside it (its own and orphans)."""
    path = Path(path)
    pattern = re.compile(re.escape(path.name) + rf"\.[0-9a-f]{{{NAME_DIGITS}}}" + re.escape(suffix))
    if not path.parent.is_dir():
        return []
    return sorted(p for p in path.parent.iterdir() if pattern.fullmatch(p.name) and p.is_file())


def companion_of(path: str | Path, suffix: str) -> Path | None:
    """The companion ``suffix`` of the header now at ``path`` (named by its bytes), or None if it has none."""
    path = Path(path)
    try:
        header = path.read_bytes()
    except OSError:
        return None
    found = companion_path(path, header, suffix)
    return found if found.is_file() else None


def write_with_companions(path: str | Path, header: bytes, companions: Mapping[str, bytes | None]) -> list[Path]:
    """Write a header and its companions so that they are replaced as one.

    Args:
        path: The header's file.
        header: The header's bytes (unchanged by its companions).
        companions: The content of each companion, by suffix (``".csv"``); None: this
            header has none of that kind (an older header's is removed).

    If writing the header fails, the companions it wrote are removed (unless they were
    already there: the same header as before).

    Returns:
        The companions' paths, in the order of ``companions`` (those given).

    """
    path = Path(path)
    written = {suffix: companion_path(path, header, suffix) for suffix, data in companions.items() if data is not None}
    created = [p for p in written.values() if not p.exists()]
    try:
        for suffix, target in written.items():
            content = companions[suffix]
            assert content is not None
            write_atomic(target, content)
        write_atomic(path, header)
    except BaseException:
        for made in created:
            made.unlink(missing_ok=True)
        raise
    for suffix in companions:
        for stale in companions_of(path, suffix):
            if stale != written.get(suffix):
                crash_point(f"before removing {stale.name}")
                stale.unlink(missing_ok=True)
    return list(written.values())
