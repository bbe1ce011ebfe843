"""Low-level reading of an MCAP file: checks, the indexed path, the linear (crash-recovery) path.

A finished file (footer and summary present) is read through its chunk indexes, skipping chunks that hold
only topics nobody asked for (images). A file without a summary (a killed or truncated run) is read record
by record from the start until the data ends or stops making sense; everything before that point is kept.
"""

from __future__ import annotations

import dataclasses
import io
import logging
import os
from collections.abc import Callable, Collection, Iterator
from dataclasses import dataclass, field
from pathlib import Path

from mcap.reader import SeekingReader
from mcap.records import Attachment, Channel, Chunk, Footer, Header, Message, Metadata, Schema
from mcap.stream_reader import MAGIC_SIZE, StreamReader, breakup_chunk
from mcap.summary import Summary

from bt_grasp.errors import LogFileError
from bt_grasp.recording import chunks

log = logging.getLogger(__name__)

MCAP_MAGIC = b"\x89MCAP0\r\n"


@dataclass(frozen=True)
class RawMessage:
    topic: str
    schema_name: str
    message_encoding: str
    log_time_ns: int
    publish_time_ns: int
    data: bytes


@dataclass
class Scan:
    """What one pass over a file found."""

    library: str = ""
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    attachments: dict[str, bytes] = field(default_factory=dict)
    messages: list[RawMessage] = field(default_factory=list)
    topic_counts: dict[str, int] = field(default_factory=dict)
    indexed: bool = False
    complete: bool = False
    header_seen: bool = False
    stop_reason: str = ""


def check_path(path: Path) -> int:
    """The file's size, after checking it exists, is a file, is readable and starts with the MCAP magic."""
    try:
        if not path.exists():
            raise LogFileError(path, "no such file")
        if path.is_dir():
            raise LogFileError(path, "is a directory, not an MCAP log file")
        size = path.stat().st_size
        if size == 0:
            raise LogFileError(path, "is empty, not an MCAP log file")
        with path.open("rb") as f:
            head = f.read(MAGIC_SIZE)
    except PermissionError as exc:
        raise LogFileError(path, "cannot be read: permission denied") from exc
    except OSError as exc:
        raise LogFileError(path, f"cannot be read: {exc.strerror or exc}") from exc
    if head != MCAP_MAGIC[: len(head)]:
        raise LogFileError(path, "is not an MCAP file (it does not start with the MCAP magic bytes)")
    if len(head) < MAGIC_SIZE:
        raise LogFileError(path, f"is cut off after {size} bytes, inside the MCAP magic bytes")
    return size


def _summary(f: io.BufferedReader, size: int) -> tuple[SeekingReader, Summary] | None:
    """The summary of a finished file, or None when the file has no valid footer or no chunk index."""
    if size < 2 * MAGIC_SIZE + 30:
        return None
    f.seek(-MAGIC_SIZE, os.SEEK_END)
    if f.read(MAGIC_SIZE) != MCAP_MAGIC:
        return None
    try:
        f.seek(0)
        reader = SeekingReader(f)
        summary = reader.get_summary()
    except Exception as exc:  # a footer that does not parse: treat the file as unfinished
        log.debug("no usable summary: %s", exc)
        return None
    if summary is None or not summary.chunk_indexes:
        return None
    return reader, summary


def _schema_name(schemas: dict[int, Schema], channel: Channel) -> str:
    schema = schemas.get(channel.schema_id)
    return schema.name if schema is not None else ""


def _scan_indexed(
    f: io.BufferedReader, reader: SeekingReader, summary: Summary, wanted: Collection[str] | None,
    budget: chunks.DecompressionBudget,
) -> Scan:
    scan = Scan(indexed=True, complete=True, header_seen=True)
    scan.library = reader.get_header().library
    for record in reader.iter_metadata():
        scan.metadata[record.name] = dict(record.metadata)
    for attachment in reader.iter_attachments():
        scan.attachments[attachment.name] = attachment.data
    counts = summary.statistics.channel_message_counts if summary.statistics else {}
    for channel in summary.channels.values():
        scan.topic_counts[channel.topic] = scan.topic_counts.get(channel.topic, 0) + counts.get(channel.id, 0)
    scan.messages.extend(_indexed_messages(f, summary, wanted, budget))
    return scan


def _indexed_messages(
    f: io.BufferedReader, summary: Summary, wanted: Collection[str] | None, budget: chunks.DecompressionBudget
) -> Iterator[RawMessage]:
    channels = summary.channels
    ids = None if wanted is None else {c.id for c in channels.values() if c.topic in wanted}
    if ids is not None and not ids:
        return
    for channel_id, log_time, publish_time, data in chunks.iter_indexed(f, summary, ids, budget):
        channel = channels[channel_id]
        yield RawMessage(channel.topic, _schema_name(summary.schemas, channel), channel.message_encoding,
                         log_time, publish_time, data)


def _scan_linear(f: io.BufferedReader, size: int, wanted: Collection[str] | None) -> Scan:
    scan = Scan()
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}

    def on_record(record: object) -> None:
        if isinstance(record, Schema):
            schemas[record.id] = record
        elif isinstance(record, Channel):
            channels[record.id] = record
            scan.topic_counts.setdefault(record.topic, 0)
        elif isinstance(record, Message):
            channel = channels.get(record.channel_id)
            if channel is None:
                raise ValueError(f"message on unknown channel {record.channel_id}")
            scan.topic_counts[channel.topic] = scan.topic_counts.get(channel.topic, 0) + 1
            if wanted is None or channel.topic in wanted:
                scan.messages.append(RawMessage(
                    channel.topic, _schema_name(schemas, channel), channel.message_encoding,
                    record.log_time, record.publish_time, record.data,
                ))

    _linear_records(f, size, scan, on_record, chunks.DecompressionBudget(size))
    return scan


def _linear_records(
    f: io.BufferedReader, size: int, scan: Scan, on_record: Callable[[object], None],
    budget: chunks.DecompressionBudget,
) -> None:
    """Feed every readable record to ``on_record``; stop quietly where the data ends or breaks."""
    f.seek(0)
    reader = StreamReader(f, emit_chunks=True, record_size_limit=size)
    footer_seen = False
    try:
        for record in reader.records:
            if isinstance(record, Header):
                scan.header_seen = True
                scan.library = record.library
            elif isinstance(record, Metadata):
                scan.metadata[record.name] = dict(record.metadata)
            elif isinstance(record, Attachment):
                scan.attachments[record.name] = record.data
            elif isinstance(record, Chunk):
                # decompressed here, bounded whatever the chunk declares; CRCs are checked by breakup_chunk:
                # a cut chunk must not yield half its messages
                plain = chunks.bounded_decompress(record.compression, record.data, record.uncompressed_size,
                                                  f.tell(), budget)
                plain_chunk = dataclasses.replace(record, compression="", data=plain)
                for inner in breakup_chunk(plain_chunk, validate_crc=True):
                    on_record(inner)
            elif isinstance(record, Footer):
                footer_seen = True  # complete only once the closing magic has been read too
            else:
                on_record(record)
        scan.complete = footer_seen
    except chunks.ChunkTooLarge:
        raise
    except Exception as exc:  # the end of a crashed or cut file shows up as any of many parse errors
        scan.stop_reason = f"{type(exc).__name__}: {exc}"
        log.debug("linear read stopped: %s", scan.stop_reason)


def scan_file(path: Path, wanted: Collection[str] | None) -> Scan:
    """Metadata, attachments, per-topic counts and the messages of the ``wanted`` topics (all if None)."""
    size = check_path(path)
    try:
        with path.open("rb") as f:
            found = _summary(f, size)
            if found is not None:
                try:
                    return _scan_indexed(f, *found, wanted, chunks.DecompressionBudget(size))
                except chunks.ChunkTooLarge:
                    raise
                except Exception as exc:  # an index that lies: fall back to reading every record
                    # not a warning on stderr: a refusal later must stay one sentence; the summary says it
                    log.info("%s: the index could not be used (%s); reading linearly", path, exc)
                    scan = _scan_linear(f, size, wanted)
                    scan.stop_reason = scan.stop_reason or f"the index could not be used ({type(exc).__name__})"
                    return scan
            return _scan_linear(f, size, wanted)
    except chunks.ChunkTooLarge as exc:
        raise LogFileError(path, str(exc)) from None


def iter_topic(path: Path, topics: Collection[str], indexed: bool) -> Iterator[RawMessage]:
    """Messages of the given topics in file order, read the same way the log was opened."""
    check_path(path)
    with path.open("rb") as f:
        size = path.stat().st_size
        found = _summary(f, size) if indexed else None
        try:
            if found is not None:
                yield from _indexed_messages(f, found[1], topics, chunks.DecompressionBudget(size))
            else:
                yield from _scan_linear(f, size, topics).messages
        except chunks.ChunkTooLarge as exc:
            raise LogFileError(path, str(exc)) from None
        except LogFileError:
            raise
        except Exception as exc:  # a chunk the index points at is damaged (the file was opened without it)
            what = ", ".join(sorted(topics))
            raise LogFileError(path, f"has damaged data where its index points for {what} "
                               f"({type(exc).__name__})") from None
