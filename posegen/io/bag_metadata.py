"""A rosbag2 folder's ``metadata.yaml``: its one reader.

Both who reads a bag (:class:`posegen.io.recorded_bag.RecordedBag`) and who is about to
replace one (:func:`posegen.io.bag_writer.check_bag_destination`) go through
:func:`read_bag_metadata`: the storage plugin, the storage files, the start time and the
provenance posegen records in ``custom_data`` when it writes a bag.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from posegen.errors import InputError, reason

PROVENANCE_KEY = "posegen"
METADATA_FILE = "metadata.yaml"


@dataclass(frozen=True)
class BagMetadata:
    """What a rosbag2's ``metadata.yaml`` says."""

    storage: str  # the storage plugin (mcap, sqlite3)
    files: tuple[Path, ...]  # the storage files, in the bag folder
    start_ns: int  # the recording's start, ns since the epoch
    compression: str  # "" or "none" when the files are not compressed
    provenance: dict[str, Any] | None  # what posegen recorded when it wrote the bag; None: not posegen's


def read_bag_metadata(path: str | Path) -> BagMetadata:
    """Read the ``metadata.yaml`` of the rosbag2 folder ``path``.

    Raises:
        InputError: No ``metadata.yaml`` there, or one that is not a rosbag2's (the cause named).

    Example:
        >>> read_bag_metadata("plans/demo/session").storage  # doctest: +SKIP
        'mcap'

    """
    path = Path(path)
    meta = path / METADATA_FILE
    if not path.is_dir() or not meta.is_file():
        raise InputError(f"{path}: not a rosbag2 directory (no {METADATA_FILE})")
    try:
        info = yaml.safe_load(meta.read_text())["rosbag2_bagfile_information"]
        storage = str(info["storage_identifier"])
        files = tuple(path / Path(str(f)).name for f in info["relative_file_paths"])
        start_ns = int(info["starting_time"]["nanoseconds_since_epoch"])
        compression = str(info.get("compression_mode") or "").lower()
        custom = info.get("custom_data") or {}
        written = custom.get(PROVENANCE_KEY) if isinstance(custom, dict) else None
        provenance = json.loads(written) if isinstance(written, str) else None
    except (OSError, UnicodeDecodeError, yaml.YAMLError, KeyError, TypeError, ValueError) as exc:  # JSON too
        raise InputError(f"{path}: not a rosbag2 bag ({METADATA_FILE}: {reason(exc)})") from exc
    bad = next((f.name for f in files if not f.name or f.name in (".", "..") or len(f.name.encode()) > 255), None)
    if bad is not None:
        raise InputError(f"{path}: not a rosbag2 bag ({METADATA_FILE}: storage file name {bad[:40]!r} is no file's)")
    if provenance is not None and not isinstance(provenance, dict):
        provenance = None
    return BagMetadata(storage, files, start_ns, compression, provenance)
