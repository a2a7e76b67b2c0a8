"""Indexed MCAP files read chunk by chunk, a channel's messages located all at once.

posegen reads hundreds of thousands of small messages of a few topics. Walking them one
record at a time in Python (as ``rosbags`` and ``mcap`` do) takes 5-12 s for a 10-minute
500 Hz session; the summary section of an indexed MCAP file says where every chunk is
(chunk index records) and each chunk's message index says where every message of a
channel lies in it, so the offsets come out as numpy arrays and the messages are
gathered without a Python loop. Records used (MCAP specification, version 0): footer
0x02, channel 0x04, message 0x05, chunk 0x06, message index 0x07, chunk index 0x08.

A file without chunk indexes (unchunked, or written without a summary) is not read
here: :func:`channels` returns None and the caller uses a record-by-record reader.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

import numpy as np
from numpy.typing import NDArray

from posegen.errors import InputError

MAGIC = b"\x89MCAP0\r\n"
OP_FOOTER, OP_CHANNEL, OP_MESSAGE, OP_CHUNK, OP_MESSAGE_INDEX, OP_CHUNK_INDEX = 0x02, 0x04, 0x05, 0x06, 0x07, 0x08
RECORD_HEAD = 9  # opcode u8 + content length u64
MESSAGE_HEAD = 22  # channel id u16, sequence u32, log time u64, publish time u64
FOOTER_SIZE = RECORD_HEAD + 20


@dataclass(frozen=True)
class Batch:
    """Messages of one channel stored together (one chunk of an MCAP file, or a run read by rosbags)."""

    buffer: NDArray[np.uint8]  # the bytes the messages are in
    offsets: NDArray[np.int64]  # (n,) start of each message's data in ``buffer``
    lengths: NDArray[np.int64]  # (n,) bytes of each message's data
    log_times: NDArray[np.int64]  # (n,) ns

    def __len__(self) -> int:
        return len(self.offsets)


@dataclass(frozen=True)
class ChunkEntry:
    """Where a chunk and its message indexes are."""

    start: int  # file offset of the chunk record
    index_offsets: dict[int, int]  # channel id -> file offset of its message index record
    compression: str


@dataclass(frozen=True)
class Summary:
    """What an indexed MCAP file holds."""

    topics: dict[str, int]  # topic -> channel id
    chunks: tuple[ChunkEntry, ...]


class _Cursor:
    """Little-endian fields read in sequence from bytes."""

    def __init__(self, data: bytes, offset: int = 0) -> None:
        self.data, self.offset = data, offset

    def take(self, fmt: str) -> int:
        (value,) = struct.unpack_from(fmt, self.data, self.offset)
        self.offset += struct.calcsize(fmt)
        return int(value)

    def raw(self, size: int) -> bytes:
        value = self.data[self.offset : self.offset + size]
        self.offset += size
        return value

    def string(self) -> str:
        return self.raw(self.take("<I")).decode()


def _read(handle: BinaryIO, offset: int, size: int, path: Path) -> bytes:
    handle.seek(offset)
    data = handle.read(size)
    if len(data) != size:
        raise InputError(f"{path}: truncated MCAP file (a record ends past the end of the file)")
    return data


def read_summary(path: Path) -> Summary | None:
    """Channels and chunk indexes of an MCAP file; None when it has no chunk index.

    Raises:
        InputError: Not an MCAP file, or truncated (no footer).

    """
    with path.open("rb") as handle:
        size = handle.seek(0, 2)
        if size < 2 * len(MAGIC) + FOOTER_SIZE or _read(handle, 0, len(MAGIC), path) != MAGIC:
            raise InputError(f"{path}: not an MCAP file")
        tail = _read(handle, size - len(MAGIC) - FOOTER_SIZE, FOOTER_SIZE + len(MAGIC), path)
        if tail[-len(MAGIC) :] != MAGIC or tail[0] != OP_FOOTER:
            raise InputError(f"{path}: truncated MCAP file (no footer; was the recording interrupted?)")
        summary_start = struct.unpack_from("<Q", tail, RECORD_HEAD)[0]
        if summary_start == 0:
            return None
        summary = _read(handle, summary_start, size - len(MAGIC) - FOOTER_SIZE - summary_start, path)
    topics: dict[str, int] = {}
    chunks: list[ChunkEntry] = []
    cursor = _Cursor(summary)
    while cursor.offset < len(summary):
        opcode, length = cursor.take("<B"), cursor.take("<Q")
        record = _Cursor(cursor.raw(length))
        if opcode == OP_CHANNEL:
            channel = record.take("<H")
            record.take("<H")  # schema id
            topics[record.string()] = channel
        elif opcode == OP_CHUNK_INDEX:
            record.raw(16)  # message start and end time
            start = record.take("<Q")
            record.raw(8)  # chunk length
            entries = record.raw(record.take("<I"))
            index = {c: o for c, o in struct.iter_unpack("<HQ", entries)}
            record.raw(8)  # message index length
            chunks.append(ChunkEntry(start, index, record.string()))
    return Summary(topics, tuple(chunks)) if chunks else None


def _decompress(data: bytes, compression: str, path: Path) -> bytes:
    if compression == "":
        return data
    if compression == "zstd":
        try:
            from compression import zstd  # Python >= 3.14
        except ImportError:
            from backports import zstd  # installed with rosbags
        return bytes(zstd.decompress(data))
    if compression == "lz4":
        import lz4.frame  # installed with rosbags

        return bytes(lz4.frame.decompress(data))
    raise InputError(f"{path}: unsupported MCAP chunk compression '{compression}' (valid: none, zstd, lz4)")


def _chunk_records(handle: BinaryIO, chunk: ChunkEntry, path: Path) -> bytes:
    """The uncompressed records of a chunk, CRC-checked when the file has a CRC."""
    head = _Cursor(_read(handle, chunk.start, RECORD_HEAD + 32, path))
    if head.take("<B") != OP_CHUNK:
        raise InputError(f"{path}: corrupt MCAP file (no chunk at offset {chunk.start})")
    head.take("<Q")
    head.raw(16)  # message start and end time
    size, crc = head.take("<Q"), head.take("<I")
    if head.take("<I") != len(chunk.compression):
        raise InputError(f"{path}: corrupt MCAP file (chunk at offset {chunk.start} disagrees with its index)")
    base = chunk.start + RECORD_HEAD + 32 + len(chunk.compression)
    stored = struct.unpack("<Q", _read(handle, base, 8, path))[0]
    records = _decompress(_read(handle, base + 8, stored, path), chunk.compression, path)
    if len(records) != size or (crc and zlib.crc32(records) != crc):
        raise InputError(f"{path}: corrupt MCAP chunk at offset {chunk.start} (size or CRC mismatch)")
    return records


def batches(path: Path, summary: Summary, channels: Sequence[int]) -> Iterator[tuple[int, Batch]]:
    """(channel id, batch) for every chunk holding messages of the given channels, in file order.

    Each chunk is read and decompressed once, whatever the number of channels.

    Raises:
        InputError: A chunk or message index is corrupt or cut short.

    """
    with path.open("rb") as handle:
        for chunk in summary.chunks:
            wanted = [c for c in channels if c in chunk.index_offsets]
            if not wanted:
                continue
            records = np.frombuffer(_chunk_records(handle, chunk, path), dtype=np.uint8)
            for channel in wanted:
                head = _read(handle, chunk.index_offsets[channel], RECORD_HEAD + 6, path)
                if head[0] != OP_MESSAGE_INDEX:
                    raise InputError(f"{path}: corrupt MCAP message index in the chunk at offset {chunk.start}")
                count = struct.unpack_from("<I", head, RECORD_HEAD + 2)[0] // 16
                index = np.frombuffer(
                    _read(handle, chunk.index_offsets[channel] + RECORD_HEAD + 6, 16 * count, path), dtype="<u8"
                ).reshape(count, 2)
                starts = index[:, 1].astype(np.int64)
                if count and (starts.max() + RECORD_HEAD + MESSAGE_HEAD > len(records)):
                    raise InputError(f"{path}: corrupt MCAP message index in the chunk at offset {chunk.start}")
                heads = np.lib.stride_tricks.sliding_window_view(records, RECORD_HEAD + 2)[starts]  # (n, 11)
                lengths = np.ascontiguousarray(heads[:, 1:9]).view("<u8").reshape(count).astype(np.int64)
                ids = np.ascontiguousarray(heads[:, 9:11]).view("<u2").reshape(count)
                offsets = starts + RECORD_HEAD + MESSAGE_HEAD
                if (
                    np.any(heads[:, 0] != OP_MESSAGE)
                    or np.any(ids != channel)
                    or np.any(offsets + lengths - MESSAGE_HEAD > len(records))
                ):
                    raise InputError(f"{path}: corrupt MCAP message index in the chunk at offset {chunk.start}")
                yield channel, Batch(records, offsets, lengths - MESSAGE_HEAD, index[:, 0].astype(np.int64))
