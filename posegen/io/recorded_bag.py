"""Recorded sessions as rosbag2: joint states and wrist wrenches, read and written.

A rosbag2 is a directory with a ``metadata.yaml`` and storage files (MCAP or sqlite3).
Bags are opened with ``rosbags`` (metadata, storage plugins, compression). The messages of
an indexed MCAP file are located with :mod:`posegen.io.mcap_index` and decoded as columns
with :mod:`posegen.io.cdr` (a 10-minute 500 Hz session in about a second); other storage
goes through ``rosbags``' message iterator. A message whose layout differs from the first
of its topic is deserialised on its own, never guessed.

Times are seconds from the bag's start, taken from the header stamps (or from the
recording times when a topic leaves its stamps at zero); every series is sorted by time.
A clock that goes back (stamps, in recording order, earlier than one already seen by
more than :data:`CLOCK_BACK_TOLERANCE_S`) is an error naming the topic and the jump, as
are joint states that are not finite numbers; wrench samples that are not finite are
left out, and said (a warning with their number).
"""

from __future__ import annotations

import hashlib
import logging
import threading
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from posegen.errors import InputError, reason
from posegen.extras import Extra, require
from posegen.io import cdr, mcap_index
from posegen.io.bag_metadata import read_bag_metadata
from posegen.io.bag_writer import writing_bag
from posegen.io.cdr import FloatArray

LOG = logging.getLogger(__name__)

JOINT_STATE = "sensor_msgs/msg/JointState"
WRENCH_STAMPED = "geometry_msgs/msg/WrenchStamped"
STORAGES = ("mcap", "sqlite3")
_BATCH = 4096  # messages per batch on the message-by-message path
CLOCK_BACK_TOLERANCE_S = 0.05  # stamps logged a little out of order are sorted; a clock going back further is refused


@dataclass(frozen=True)
class JointStates:
    """A ``sensor_msgs/JointState`` topic."""

    names: tuple[str, ...]  # joint names, in the topic's order
    times_s: FloatArray  # (n,) s from the bag's start, increasing
    positions: FloatArray  # (n, nj) rad, columns in ``names`` order


@dataclass(frozen=True)
class Wrenches:
    """A ``geometry_msgs/WrenchStamped`` topic."""

    times_s: FloatArray  # (m,) s from the bag's start, increasing
    forces: FloatArray  # (m, 3) N, sensor frame
    torques: FloatArray  # (m, 3) N m, sensor frame


def _typestore() -> Any:
    require(Extra.ROS, "reading rosbag2 bags")
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_HUMBLE)


class _Topic:
    """Decodes one topic's batches into stamped values: columns where it can, one by one where not."""

    def __init__(self, topic: str, msgtype: str) -> None:
        self.topic, self.msgtype = topic, msgtype
        self._store: Any = None  # rosbags' deserialiser, made when a message needs it
        self.layout: cdr.Layout | None = None
        self.names: tuple[str, ...] = ()
        self.parts: list[tuple[NDArray[np.int64], NDArray[np.int64], FloatArray]] = []  # stamps, log times, values

    def _first(self, message: Any) -> None:
        frame_id = message.header.frame_id
        if self.msgtype == WRENCH_STAMPED:
            self.layout = cdr.wrench_stamped_layout(frame_id)
            return
        self.names = tuple(message.name)
        if len(message.position) != len(self.names) or len(set(self.names)) != len(self.names):
            raise InputError(
                f"topic '{self.topic}': {len(message.position)} positions for {len(self.names)} joint names"
                + ("" if len(set(self.names)) == len(self.names) else " (a name repeats)")
            )
        counts = (len(message.position), len(message.velocity), len(message.effort))
        self.layout = cdr.joint_state_layout(self.names, frame_id, counts)

    def _values(self, message: Any, log_time: int) -> FloatArray:
        """Values of one message deserialised on its own."""
        if self.msgtype == WRENCH_STAMPED:
            w = message.wrench
            return np.array([w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z])
        names = tuple(message.name)
        if sorted(names) != sorted(self.names) or len(message.position) != len(names):
            raise InputError(
                f"topic '{self.topic}': the message recorded at {log_time * 1e-9:.3f} s names other joints "
                f"({len(names)} names, {len(message.position)} positions) than the first one"
            )
        column = {name: k for k, name in enumerate(names)}
        return np.asarray(message.position, dtype=float)[[column[n] for n in self.names]]

    def _deserialise(self, batch: mcap_index.Batch, k: int) -> Any:
        """Message ``k`` of a batch, deserialised by rosbags."""
        if self._store is None:
            self._store = _typestore()
        start = int(batch.offsets[k])
        return self._store.deserialize_cdr(batch.buffer[start : start + int(batch.lengths[k])].tobytes(), self.msgtype)

    def add(self, batch: mcap_index.Batch) -> None:
        if self.layout is None and len(batch):
            self._first(self._deserialise(batch, 0))
        layout = self.layout
        if layout is None:
            return
        decoded = batch.lengths == layout.size
        if np.any(decoded):
            rows = np.lib.stride_tricks.sliding_window_view(batch.buffer, layout.size)[batch.offsets[decoded]]
            ok = cdr.matches(layout, rows)
            if not np.all(ok):
                decoded[np.flatnonzero(decoded)[~ok]] = False
                rows = rows[ok]
            stamps, blocks = cdr.decode(layout, rows, [0] if self.msgtype == JOINT_STATE else None)
            self.parts.append((stamps, batch.log_times[decoded], np.hstack(blocks)))
        for k in np.flatnonzero(~decoded).tolist():
            message = self._deserialise(batch, k)
            stamp = np.array([message.header.stamp.sec * 1_000_000_000 + message.header.stamp.nanosec])
            self.parts.append((stamp, batch.log_times[[k]], self._values(message, int(batch.log_times[k]))[None, :]))

    def _checked(
        self, stamps: NDArray[np.int64], values: FloatArray, origin_ns: int, where: Path
    ) -> tuple[NDArray[np.int64], FloatArray]:
        """The samples, in recording order, once the clock and the values are checked (see the module docstring).

        Raises:
            InputError: The clock goes back, or joint states (or every wrench) not finite.

        """
        back = np.maximum.accumulate(stamps) - stamps  # ns behind the latest stamp seen, in recording order
        if back.max() > CLOCK_BACK_TOLERANCE_S * 1e9:
            k = int(np.argmax(back > CLOCK_BACK_TOLERANCE_S * 1e9))
            raise InputError(
                f"{where}: topic '{self.topic}': the clock goes back {back.max() * 1e-9:.3f} s at message {k} "
                f"({(stamps[k] - origin_ns) * 1e-9:.3f} s): one recording has one clock, forward"
            )
        finite = np.isfinite(values).all(axis=1)
        if finite.all():
            return stamps, values
        first = f"first at {(stamps[~finite][0] - origin_ns) * 1e-9:.3f} s"
        count = f"{int((~finite).sum())} of {len(values)} messages"
        if self.msgtype == JOINT_STATE or not finite.any():
            raise InputError(f"{where}: topic '{self.topic}': {count} hold values that are not finite ({first})")
        LOG.warning(
            "%s: topic '%s': %s hold values that are not finite (%s): left out", where, self.topic, count, first
        )
        return stamps[finite], values[finite]

    def series(self, origin_ns: int, where: Path) -> tuple[FloatArray, FloatArray]:
        """Times (n,) in s from ``origin_ns`` and values (n, k), sorted by time."""
        if not self.parts:
            raise InputError(f"{where}: topic '{self.topic}' has no message")
        logged = np.argsort(np.concatenate([p[1] for p in self.parts]), kind="stable")  # recording order
        stamps = np.concatenate([p[0] for p in self.parts])[logged]
        if not np.any(stamps):
            stamps = np.concatenate([p[1] for p in self.parts])[logged]  # never stamped: the recording times
        values = np.concatenate([p[2] for p in self.parts])[logged]
        stamps, values = self._checked(stamps, values, origin_ns, where)
        if np.any(np.diff(stamps) < 0):
            order = np.argsort(stamps, kind="stable")
            stamps, values = stamps[order], values[order]
        return (stamps - origin_ns) * 1e-9, values


class RecordedBag:
    """A rosbag2 directory, checked when opened.

    Raises:
        InputError: Not a rosbag2 directory, an unknown storage plugin, or a storage file
            that is missing, truncated or unreadable.

    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        meta = read_bag_metadata(self.path)
        self.storage, self.files, self.start_ns = meta.storage, meta.files, meta.start_ns
        self.provenance: dict[str, Any] | None = meta.provenance
        compression = meta.compression
        if self.storage not in STORAGES:
            raise InputError(f"{self.path}: unknown storage plugin {self.storage!r}; valid: {', '.join(STORAGES)}")
        missing = [f.name for f in self.files if not f.is_file()]
        if missing or not self.files:
            raise InputError(f"{self.path}: storage file missing: {', '.join(missing) or 'none listed'}")
        indexed = self.storage == "mcap" and compression in ("", "none")
        self.summaries = [mcap_index.read_summary(f) for f in self.files] if indexed else []
        require(Extra.ROS, "reading rosbag2 bags")
        try:
            from rosbags.rosbag2 import Reader

            with Reader(self.path) as reader:
                self.topics = {c.topic: c.msgtype for c in reader.connections}
        except Exception as exc:  # rosbags raises several types for unreadable storage
            raise InputError(f"{self.path}: cannot read the bag ({reason(exc)})") from exc

    def require(self, topic: str, msgtype: str) -> None:
        """Check that the bag has ``topic`` with messages of ``msgtype``.

        Raises:
            InputError: The topic is missing (the bag's topics are listed) or of another type.

        """
        if topic not in self.topics:
            listed = ", ".join(f"{t} ({m})" for t, m in sorted(self.topics.items())) or "none"
            raise InputError(f"{self.path}: no topic '{topic}'; its topics: {listed}")
        if self.topics[topic] != msgtype:
            raise InputError(f"{self.path}: topic '{topic}' holds {self.topics[topic]}, expected {msgtype}")

    def _batches(self, topics: Sequence[str]) -> Iterator[tuple[str, mcap_index.Batch]]:
        if self.summaries and all(s is not None for s in self.summaries):
            for file, summary in zip(self.files, self.summaries, strict=True):
                assert summary is not None
                by_id = {summary.topics[t]: t for t in topics if t in summary.topics}
                for channel, batch in mcap_index.batches(file, summary, list(by_id)):
                    yield by_id[channel], batch
            return
        from rosbags.rosbag2 import Reader

        pending: dict[str, list[tuple[int, bytes]]] = {t: [] for t in topics}
        with Reader(self.path) as reader:
            connections = [c for c in reader.connections if c.topic in pending]
            for connection, log_time, raw in reader.messages(connections=connections):
                pending[connection.topic].append((log_time, bytes(raw)))
                if len(pending[connection.topic]) == _BATCH:
                    yield connection.topic, _batch(pending[connection.topic])
                    pending[connection.topic] = []
        for topic, messages in pending.items():
            if messages:
                yield topic, _batch(messages)

    def read(self, joint_topic: str, wrench_topics: Sequence[str] = ()) -> tuple[JointStates, list[Wrenches]]:
        """Read the joint states and the wrenches in one pass over the bag.

        Raises:
            InputError: A topic is missing, of another type or empty, or its messages are
                inconsistent (joint names that change, positions missing).

        """
        self.require(joint_topic, JOINT_STATE)
        for topic in wrench_topics:
            self.require(topic, WRENCH_STAMPED)
        decoders = {joint_topic: _Topic(joint_topic, JOINT_STATE)}
        decoders.update({t: _Topic(t, WRENCH_STAMPED) for t in wrench_topics})
        try:
            for topic, batch in self._batches(list(decoders)):
                decoders[topic].add(batch)
        except InputError:
            raise
        except Exception as exc:  # a corrupt message or storage file
            raise InputError(f"{self.path}: cannot read the bag ({reason(exc)})") from exc
        times, positions = decoders[joint_topic].series(self.start_ns, self.path)
        joints = JointStates(decoders[joint_topic].names, times, positions)
        wrenches = []
        for topic in wrench_topics:
            at, values = decoders[topic].series(self.start_ns, self.path)
            wrenches.append(Wrenches(at, values[:, :3], values[:, 3:]))
        return joints, wrenches

    def sha256(self) -> str:
        """sha256 of the metadata and the storage files, in that order."""
        digest = hashlib.sha256()
        for file in (self.path / "metadata.yaml", *self.files):
            with file.open("rb") as handle:
                while block := handle.read(1 << 22):
                    digest.update(block)
        return digest.hexdigest()

    def read_and_hash(
        self, joint_topic: str, wrench_topics: Sequence[str] = ()
    ) -> tuple[JointStates, list[Wrenches], str]:
        """:meth:`read`, and :meth:`sha256` computed in a thread meanwhile (hashing releases the GIL)."""
        digest: list[str] = []
        worker = threading.Thread(target=lambda: digest.append(self.sha256()), daemon=True)
        worker.start()
        try:
            joints, wrenches = self.read(joint_topic, wrench_topics)
        finally:
            worker.join()
        if not digest:
            raise InputError(f"{self.path}: cannot read the bag's files to hash them")
        return joints, wrenches, digest[0]


def _batch(messages: list[tuple[int, bytes]]) -> mcap_index.Batch:
    lengths = np.array([len(raw) for _, raw in messages], dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum(lengths)[:-1]]).astype(np.int64)
    buffer = np.frombuffer(b"".join(raw for _, raw in messages), dtype=np.uint8)
    return mcap_index.Batch(buffer, offsets, lengths, np.array([t for t, _ in messages], dtype=np.int64))


def write_recording(
    path: str | Path,
    joints: JointStates,
    joint_topic: str,
    wrenches: dict[str, Wrenches],
    provenance: dict[str, Any],
    start_ns: int = 0,
    extra: Mapping[str, str] | None = None,
) -> None:
    """Write joint states and wrenches as a rosbag2 (MCAP), messages interleaved in time order.

    Args:
        path: Bag directory (replaced if it is a bag).
        joints: Joint states; their velocities are the positions' time derivative.
        joint_topic: Topic of the joint states.
        wrenches: Wrench series by topic.
        provenance: Recorded in the bag's metadata.
        start_ns: Clock time of ``times_s == 0``.
        extra: Text files written into the bag directory with it, by file name (all swapped in as one).

    """
    names = list(joints.names)
    stamps = start_ns + np.round(joints.times_s * 1e9).astype(np.int64)
    velocities = np.gradient(joints.positions, joints.times_s, axis=0)
    layout = cdr.joint_state_layout(names)
    streams = [
        (joint_topic, stamps, cdr.encode(layout, stamps, [joints.positions, velocities, np.zeros((len(stamps), 0))]))
    ]
    wrench = cdr.wrench_stamped_layout()
    for topic, series in wrenches.items():
        at = start_ns + np.round(series.times_s * 1e9).astype(np.int64)
        streams.append((topic, at, cdr.encode(wrench, at, [series.forces, series.torques])))
    with writing_bag(path, provenance, extra) as writer:
        writer.topic(joint_topic, JOINT_STATE)
        for topic in wrenches:
            writer.topic(topic, WRENCH_STAMPED)
        writer.interleaved(streams)
