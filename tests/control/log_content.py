"""What two logs of the same run share, byte for byte, once the wall clock is taken out.

A log carries the run's start date: ``time_origin_ns`` (and ``start_unix_ns``) in the metadata, every message's
log and publish time (origin + simulated time) and the timestamps inside Foxglove's protobuf messages; the
command line (``command_line``) and the HEAD commit (``git_commit``) when it started; and a few wall-clock
durations: ``/run/result``'s ``wall_time_s`` and
``planning.wall_s``, the log's own path there, and ``/log`` lines quoting milliseconds. :func:`content` returns
everything else exactly: every channel with its schema bytes, every message's topic, simulated times, sequence
and bytes (protobuf messages with their timestamps moved to simulated time, re-serialised deterministically),
the metadata and every attachment.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from google.protobuf.timestamp_pb2 import Timestamp
from mcap.reader import make_reader

from bt_grasp.recording.schemas import PROTOBUF_CLASSES

#: metadata keys that hold the start date, the command line (``--interactive`` is on it) and the repository's HEAD
#: when the run started (two runs in one test process run the same code; a commit landing between them in a
#: shared checkout changes only this)
WALL_METADATA = ("time_origin_ns", "start_unix_ns", "command_line", "git_commit")
_MS = re.compile(r"\d+ ms")


@dataclass(frozen=True)
class LogContent:
    metadata: dict[str, dict[str, str]]
    attachments: list[tuple[str, bytes]]
    channels: list[tuple[str, str, str, str, bytes]]
    messages: list[tuple[str, int, int, int, bytes]]

    @property
    def topics(self) -> list[str]:
        return [c[0] for c in self.channels]


def _to_sim_time(message: Any, origin: int) -> None:
    for _field, value in message.ListFields():
        items = list(value) if type(value).__name__.startswith("Repeated") else [value]
        for item in items:
            if isinstance(item, Timestamp):
                item.FromNanoseconds(item.ToNanoseconds() - origin)
            elif hasattr(item, "ListFields"):
                _to_sim_time(item, origin)


def _result(data: bytes) -> bytes:
    result = json.loads(data)
    for key in ("wall_time_s", "log"):
        result.pop(key, None)
    if isinstance(result.get("planning"), dict):
        result["planning"].pop("wall_s", None)
    return json.dumps(result, sort_keys=True).encode()


def content(path: Path) -> LogContent:
    with path.open("rb") as f:
        reader = make_reader(f)
        metadata = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        origin = int(metadata["bt_grasp.run"]["time_origin_ns"])
        for key in WALL_METADATA:
            metadata["bt_grasp.run"].pop(key, None)
        attachments = [(a.name, a.data) for a in reader.iter_attachments()]
        summary = reader.get_summary()
        assert summary is not None, f"{path} is not finished"
        channels = sorted(
            (c.topic, c.message_encoding, summary.schemas[c.schema_id].name, summary.schemas[c.schema_id].encoding,
             summary.schemas[c.schema_id].data) for c in summary.channels.values())
        messages = []
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            data = message.data
            if channel.message_encoding == "protobuf" and schema is not None:
                decoded = PROTOBUF_CLASSES[schema.name]()
                decoded.ParseFromString(data)
                _to_sim_time(decoded, origin)
                if channel.topic == "/log":
                    decoded.message = _MS.sub("N ms", decoded.message)
                data = decoded.SerializeToString(deterministic=True)
            elif channel.topic == "/run/result":
                data = _result(data)
            messages.append((channel.topic, message.log_time - origin, message.publish_time - origin,
                             message.sequence, data))
    return LogContent(metadata, attachments, channels, messages)
