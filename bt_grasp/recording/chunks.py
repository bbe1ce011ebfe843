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


def _decompress(compression: str, data: bytes, size: int, zstd: zstandard.ZstdDecompressor) -> bytes:
    if compression == "":
        return data
    if compression == "zstd":
        return zstd.decompress(data, max_output_size=size)
    if compression == "lz4" and lz4_frame is not None:
        return bytes(lz4_frame.decompress(data))
    raise ValueError(f"unsupported chunk compression {compression!r}")


def iter_indexed(f: BinaryIO, summary: Summary, channel_ids: Collection[int] | None) -> Iterator[RawTuple]:
    """Messages of the given channels (all if None), in file order, from the chunks the index lists."""
    zstd = zstandard.ZstdDecompressor()
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
        records = _decompress(compression, buf[pos: pos + data_len], size, zstd)
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
