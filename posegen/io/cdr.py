"""Fixed-layout CDR: many ROS 2 sensor messages of one layout, encoded and decoded as columns.

A ``sensor_msgs/msg/JointState`` whose joint names and frame id stay the same (as a joint
state broadcaster publishes them), or a ``geometry_msgs/msg/WrenchStamped`` whose frame id
stays the same, has one byte layout: every message has the same length and the same bytes
everywhere but the stamp and the float64 arrays. Encoding n messages fills the columns of
an (n, L) byte table; decoding reads them back after checking every fixed byte against the
layout, so that a message of another layout is never misread (the caller deserialises
those one by one).

CDR (ROS 2's serialisation, little endian here): a 4-byte encapsulation header, then the
fields in order, each aligned to its size counted from the start of the body; a string is
a uint32 length (with the terminating NUL) and its bytes; a sequence is a uint32 count and
its elements (no alignment padding when it is empty).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from posegen.numeric import FloatArray

ENCAPSULATION = b"\x00\x01\x00\x00"  # CDR, little endian
STAMP = slice(4, 12)  # builtin_interfaces/Time (int32 sec, uint32 nanosec): first field of a header

ByteRows = NDArray[np.uint8]  # (n, L): one message per row
Nanoseconds = NDArray[np.int64]


@dataclass(frozen=True)
class Layout:
    """The byte layout shared by a run of messages of one type."""

    template: bytes  # one message, stamp and floats zero
    blocks: tuple[tuple[int, int], ...]  # (byte offset, number of float64) of each float array, in field order

    @property
    def size(self) -> int:
        """Bytes per message."""
        return len(self.template)

    def fixed_runs(self) -> list[tuple[int, int]]:
        """[start, stop) byte ranges that every message of this layout shares with the template."""
        variable = [(STAMP.start, STAMP.stop)] + [(offset, offset + 8 * count) for offset, count in self.blocks]
        runs, start = [], 0
        for low, high in sorted(variable):
            if low > start:
                runs.append((start, low))
            start = max(start, high)
        if start < self.size:
            runs.append((start, self.size))
        return runs


class _Body:
    """A CDR body under construction."""

    def __init__(self) -> None:
        self.data = bytearray()

    def align(self, size: int) -> None:
        self.data.extend(bytes(-len(self.data) % size))

    def uint32(self, value: int) -> None:
        self.align(4)
        self.data.extend(int(value).to_bytes(4, "little"))

    def string(self, text: str) -> None:
        encoded = text.encode() + b"\0"
        self.uint32(len(encoded))
        self.data.extend(encoded)

    def header(self, frame_id: str) -> None:
        self.data.extend(bytes(8))  # stamp
        self.string(frame_id)

    def floats(self, count: int) -> int:
        """Reserve ``count`` float64; return their byte offset in the message."""
        if count:
            self.align(8)
        offset = len(ENCAPSULATION) + len(self.data)
        self.data.extend(bytes(8 * count))
        return offset

    def layout(self, blocks: Sequence[tuple[int, int]]) -> Layout:
        return Layout(ENCAPSULATION + bytes(self.data), tuple(blocks))


def joint_state_layout(names: Sequence[str], frame_id: str = "", counts: Sequence[int] | None = None) -> Layout:
    """Layout of ``sensor_msgs/msg/JointState``; its blocks are position, velocity, effort.

    Args:
        names: Joint names, in message order.
        frame_id: Header frame id.
        counts: Lengths of the position, velocity and effort arrays (default: a position
            and a velocity per joint, no effort).

    """
    body = _Body()
    body.header(frame_id)
    body.uint32(len(names))
    for name in names:
        body.string(name)
    blocks = []
    for count in (len(names), len(names), 0) if counts is None else counts:
        body.uint32(count)
        blocks.append((body.floats(count), count))
    return body.layout(blocks)


def wrench_stamped_layout(frame_id: str = "") -> Layout:
    """Layout of ``geometry_msgs/msg/WrenchStamped``; its blocks are force (N) and torque (N m)."""
    body = _Body()
    body.header(frame_id)
    force = body.floats(3)
    torque = body.floats(3)
    return body.layout([(force, 3), (torque, 3)])


def encode(layout: Layout, stamps_ns: Nanoseconds, arrays: Sequence[FloatArray]) -> ByteRows:
    """Serialise n messages of one layout.

    Args:
        layout: Their layout.
        stamps_ns: (n,) header stamps in ns.
        arrays: One (n, count) array per block of the layout, in its order.

    Returns:
        (n, L) bytes, one message per row.

    """
    stamps = np.asarray(stamps_ns, dtype=np.int64)
    n = len(stamps)
    rows = np.empty((n, layout.size), dtype=np.uint8)
    rows[:] = np.frombuffer(layout.template, dtype=np.uint8)
    sec, nanosec = np.divmod(stamps, 1_000_000_000)
    rows[:, 4:8] = sec.astype("<i4").view(np.uint8).reshape(n, 4)
    rows[:, 8:12] = nanosec.astype("<u4").view(np.uint8).reshape(n, 4)
    for (offset, count), values in zip(layout.blocks, arrays, strict=True):
        block = np.ascontiguousarray(np.asarray(values, dtype="<f8").reshape(n, count))
        rows[:, offset : offset + 8 * count] = block.view(np.uint8).reshape(n, 8 * count)
    return rows


def matches(layout: Layout, rows: ByteRows) -> NDArray[np.bool_]:
    """(n,) whether each message (a row of L bytes) has this layout's fixed bytes."""
    template = np.frombuffer(layout.template, dtype=np.uint8)
    ok = np.ones(len(rows), dtype=bool)
    for start, stop in layout.fixed_runs():
        ok &= np.all(rows[:, start:stop] == template[start:stop], axis=1)
    return ok


def decode(layout: Layout, rows: ByteRows, blocks: Sequence[int] | None = None) -> tuple[Nanoseconds, list[FloatArray]]:
    """Stamps (n,) in ns and one (n, count) array per requested block of n messages of this layout.

    Args:
        layout: Their layout (check the rows with :func:`matches` first).
        rows: (n, L) messages.
        blocks: Indices of the blocks to decode (default: all).

    """
    n = len(rows)
    sec = np.ascontiguousarray(rows[:, 4:8]).view("<i4").reshape(n).astype(np.int64)
    nanosec = np.ascontiguousarray(rows[:, 8:12]).view("<u4").reshape(n).astype(np.int64)
    wanted = range(len(layout.blocks)) if blocks is None else blocks
    values: list[FloatArray] = []
    for index in wanted:
        offset, count = layout.blocks[index]
        raw = np.ascontiguousarray(rows[:, offset : offset + 8 * count])
        values.append(raw.view("<f8").reshape(n, count).astype(np.float64))
    return (sec * 1_000_000_000 + nanosec).astype(np.int64), values
