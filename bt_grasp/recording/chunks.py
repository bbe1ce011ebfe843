"""A fast path through an indexed MCAP file: read the chunks the index points at, parse their messages.

The generic ``mcap`` seeking reader spends most of its time in per-field stream reads; a bt_grasp log has
one small chunk per tick, so a 10,000-tick log means 10,000 chunks. Here each chunk is read with one
``read`` call, decompressed with one reused decompressor, and its records are walked with
``struct.unpack_from`` (record layout from the MCAP specification: opcode u8, length u64, body).
"""

from __future__ import annotations

import struct
from collections.abc import Collection, Iterator
from typing import BinaryIO

import zstandard
from mcap.records import ChunkIndex
from mcap.summary import Summary

try:
    import lz4.frame as lz4_frame
except ImportError:  # lz4 is optional for reading: only lz4-compressed logs need it
    lz4_frame = None

OP_MESSAGE = 0x05
OP_CHUNK = 0x06
_RECORD = struct.Struct("<BQ")
_CHUNK_HEAD = struct.Struct("<QQQII")  # start, end, uncompressed size, crc, compression-name length
_MESSAGE_HEAD = struct.Struct("<HIQQ")  # channel, sequence, log time, publish time

RawTuple = tuple[int, int, int, bytes]  # channel id, log time, publish time, data


def _wanted_chunks(summary: Summary, channel_ids: Collection[int] | None) -> list[ChunkIndex]:
    chunks = sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)
    if channel_ids is None:
        return chunks
    return [c for c in chunks if not c.message_index_offsets or any(i in channel_ids for i in
                                                                    c.message_index_offsets)]


#: no chunk of a log may decompress to more than this (a bt_grasp chunk holds one tick: kilobytes to a few MB)
MAX_CHUNK_BYTES = 64 << 20
#: and a whole file to no more than this many times its own size, plus one chunk's worth: real logs compress
#: 2-10x; only a decompression bomb gets near it
MAX_EXPANSION = 200


class ChunkTooLarge(ValueError):
    """A chunk that would decompress past the limits: a corrupt or hostile log, refused (never allocated)."""

    def __init__(self, offset: int, problem: str) -> None:
        super().__init__(f"the chunk at byte {offset} {problem}; the log is refused (corrupt or hostile)")
        self.offset = offset


class DecompressionBudget:
    """Bytes a file may still decompress to, whatever its chunks declare (one per file read)."""

    def __init__(self, file_size: int) -> None:
        self.left = MAX_CHUNK_BYTES + MAX_EXPANSION * file_size

    def take(self, n: int, offset: int) -> None:
        self.left -= n
        if self.left < 0:
            raise ChunkTooLarge(offset, f"takes the file past {MAX_EXPANSION}x its own size once decompressed")


def bounded_decompress(compression: str, data: bytes, declared: int, offset: int, budget: DecompressionBudget) -> bytes:
    """A chunk's records, decompressed with a hard output limit that holds whatever the frame declares:
    at most the chunk's declared size, :data:`MAX_CHUNK_BYTES` and what the file's budget has left."""
    limit = min(MAX_CHUNK_BYTES, max(budget.left, 0))
    if declared > limit:
        raise ChunkTooLarge(offset, f"declares {declared} bytes uncompressed (limit {limit})")
    if compression == "":
        out = bytes(data)
    elif compression == "zstd":
        frame_size = zstandard.frame_content_size(data) if len(data) >= 18 else -1
        if frame_size > declared:
            raise ChunkTooLarge(offset, f"holds a zstd frame of {frame_size} bytes in a chunk of {declared}")
        reader = zstandard.ZstdDecompressor().stream_reader(data, read_across_frames=True)
        parts, got = [], 0
        while got <= declared:
            piece = reader.read(min(1 << 20, declared + 1 - got))
            if not piece:
                break
            parts.append(piece)
            got += len(piece)
        out = b"".join(parts)
    elif compression == "lz4" and lz4_frame is not None:
        out = bytes(lz4_frame.LZ4FrameDecompressor().decompress(data, max_length=declared + 1))
    else:
        raise ValueError(f"unsupported chunk compression {compression!r}")
    if len(out) != declared:
        raise ChunkTooLarge(offset, f"decompresses to {'more' if len(out) > declared else len(out)} bytes, not the "
                            f"{declared} it declares")
    budget.take(len(out), offset)
    return out


def iter_indexed(
    f: BinaryIO, summary: Summary, channel_ids: Collection[int] | None, budget: DecompressionBudget
) -> Iterator[RawTuple]:
    """Messages of the given channels (all if None), in file order, from the chunks the index lists."""
    wanted = None if channel_ids is None else frozenset(channel_ids)
    for index in _wanted_chunks(summary, wanted):
        f.seek(index.chunk_start_offset)
        buf = f.read(index.chunk_length)
        opcode, _length = _RECORD.unpack_from(buf, 0)
        if opcode != OP_CHUNK:
            raise ValueError(f"no chunk at offset {index.chunk_start_offset}")
        pos = _RECORD.size
        _start, _end, size, _crc, name_len = _CHUNK_HEAD.unpack_from(buf, pos)
        pos += _CHUNK_HEAD.size
        compression = buf[pos: pos + name_len].decode()
        pos += name_len
        (data_len,) = struct.unpack_from("<Q", buf, pos)
        pos += 8
        records = bounded_decompress(compression, buf[pos: pos + data_len], size, index.chunk_start_offset, budget)
        yield from _messages(records, wanted)


def _messages(records: bytes, wanted: frozenset[int] | None) -> Iterator[RawTuple]:
    pos, end = 0, len(records)
    while pos < end:
        opcode, length = _RECORD.unpack_from(records, pos)
        body = pos + _RECORD.size
        pos = body + length
        if opcode != OP_MESSAGE:
            continue
        channel, _seq, log_time, publish_time = _MESSAGE_HEAD.unpack_from(records, body)
        if wanted is None or channel in wanted:
            yield channel, log_time, publish_time, records[body + _MESSAGE_HEAD.size: pos]
