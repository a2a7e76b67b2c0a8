"""Writing rosbag2 directories (MCAP storage, rosbag2 format 9) atomically, with ``rosbags``.

The bag, with any file that goes with it (a simulated session's ``truth.yaml``), is
written under a staging folder beside its destination and swapped into place by one
rename at the end (:func:`posegen.io.atomic.swap_folder`): an interrupted run leaves no
half-written bag, a bag written before is only replaced by a complete one, and a bag
and its files always come from one run. posegen's provenance goes into ``metadata.yaml``'s
``custom_data`` (key ``posegen``, a JSON string).
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from posegen.errors import InputError
from posegen.extras import Extra, require
from posegen.io.atomic import staging_folder, swap_folder, write_atomic
from posegen.io.bag_metadata import METADATA_FILE, PROVENANCE_KEY, read_bag_metadata

BAG_FILES = ("truth.yaml",)  # what posegen writes into a bag beside its storage: a simulated session's truth


class BagWriter:
    """Topics and messages of a bag being written (see :func:`writing_bag`)."""

    def __init__(self, writer: Any) -> None:
        from rosbags.typesys import Stores, get_typestore

        self._writer = writer
        self.typestore = get_typestore(Stores.ROS2_HUMBLE)
        self._connections: dict[str, Any] = {}

    def topic(self, name: str, msgtype: str) -> None:
        """Declare a topic and its message type (e.g. ``sensor_msgs/msg/JointState``)."""
        self._connections[name] = self._writer.add_connection(name, msgtype, typestore=self.typestore)

    def message(self, topic: str, time_ns: int, message: Any) -> None:
        """Serialise and write one message (a ``rosbags`` message object) at ``time_ns``."""
        connection = self._connections[topic]
        self._writer.write(connection, int(time_ns), self.typestore.serialize_cdr(message, connection.msgtype))

    def interleaved(self, streams: Sequence[tuple[str, NDArray[np.int64], NDArray[np.uint8]]]) -> None:
        """Write already serialised messages of several topics, merged in time order.

        Args:
            streams: (topic, times (n,) in ns, messages (n, L) bytes, one per row) per topic.

        """
        times = np.concatenate([s[1] for s in streams])
        source = np.concatenate([np.full(len(s[1]), k) for k, s in enumerate(streams)])
        row = np.concatenate([np.arange(len(s[1])) for s in streams])
        order = np.argsort(times, kind="stable")
        connections = [self._connections[s[0]] for s in streams]
        rows = [s[2] for s in streams]
        write = self._writer.write
        for k in order.tolist():
            write(connections[source[k]], int(times[k]), rows[source[k]][row[k]].tobytes())


def check_bag_destination(path: str | Path) -> None:
    """Check, before any work, that a bag may be written at ``path``: nothing, an empty folder, or posegen's bag.

    A bag posegen wrote has its provenance in ``metadata.yaml`` (``custom_data``) and
    holds nothing but that file, the storage files it lists and :data:`BAG_FILES` (files,
    not folders or links); a
    recording (no posegen provenance) or a folder holding anything else (a user's notes)
    is never replaced.

    Raises:
        InputError: ``path`` exists and is not such a folder (it is never deleted).

    """
    path = Path(path)
    if not path.exists() or (path.is_dir() and not path.is_symlink() and not any(path.iterdir())):
        return
    if not path.is_dir() or not (path / METADATA_FILE).is_file():
        raise InputError(f"{path} exists and is not a rosbag2 directory: not overwriting it")
    try:
        meta = read_bag_metadata(path)
    except InputError as exc:
        raise InputError(f"{exc}: not replacing it") from exc
    if meta.provenance is None:
        raise InputError(f"{path} is a rosbag2 directory posegen did not write (a recording?): not replacing it")
    ours = {METADATA_FILE, *(f.name for f in meta.files), *BAG_FILES}
    others = sorted(p.name for p in path.iterdir() if not _written(p, ours))
    if others:
        shown = ", ".join(others[:3]) + (f" and {len(others) - 3} more" if len(others) > 3 else "")
        raise InputError(f"{path} holds files posegen did not write ({shown}): not replacing it; give another folder")


def _written(entry: Path, names: set[str]) -> bool:
    """Whether a bag folder's entry may be what posegen wrote: a file (not a folder, not a link) of ``names``."""
    return entry.name in names and entry.is_file() and not entry.is_symlink()


@contextmanager
def writing_bag(
    path: str | Path, provenance: dict[str, Any], extra: Mapping[str, str] | None = None
) -> Iterator[BagWriter]:
    """Write a rosbag2 directory at ``path``, all or nothing.

    Args:
        path: The bag directory (a bag posegen wrote there is replaced whole: :func:`check_bag_destination`).
        provenance: Recorded in ``metadata.yaml``.
        extra: Text files to write into the bag directory with it, by file name.

    Raises:
        InputError: ``path`` exists and is not an empty folder or a bag posegen wrote (it is never deleted).

    """
    require(Extra.ROS, "writing rosbag2 bags")
    from rosbags.rosbag2 import StoragePlugin, Writer

    path = Path(path)
    check_bag_destination(path)
    scratch = staging_folder(path)
    try:
        bag = scratch / path.name
        writer = Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP)
        writer.set_custom_data(PROVENANCE_KEY, json.dumps(provenance, sort_keys=True))
        with writer:
            yield BagWriter(writer)
        for name, text in (extra or {}).items():
            write_atomic(bag / name, text)
        swap_folder(bag, path)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
