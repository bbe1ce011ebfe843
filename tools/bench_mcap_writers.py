"""The same messages written three ways: bt_grasp's writer process, the `mcap` writer in-process, foxglove-sdk.

    python tools/bench_mcap_writers.py LOG.mcap [--reps 3] [--ticks N] [--json]

Reads every message of a bt_grasp log (a real run's: ``bt-grasp run ... --log LOG.mcap``) in file order, cut
into ticks at each ``/bt/tick`` message, and writes them again, tick by tick with a flush at every tick boundary
(what a run does: each tick its own chunk, so a kill loses at most one tick), through

* ``writer process``: :class:`bt_grasp.recording.writer_process.ProcessWriter` (what ``--log`` uses): the tick
  loop appends to a batch and pickles it to a feeder thread; a child process compresses and writes;
* ``mcap in-process``: ``mcap.writer.Writer`` on the calling thread (``RunRecorder(writer_process=False)``);
* ``foxglove-sdk``: ``foxglove.open_mcap`` (Rust; ``Channel.log`` of the same bytes, ``MCAPWriter.flush``
  per tick), once with its default zstd and once with compression on a thread of its own
  (``compression_threads=1``), and once without the per-tick flush (4 MiB chunks: a kill loses up to a
  chunk; shown for what the flush costs, not as an option).

Per writer, interleaved over ``--reps`` rounds (medians): the CPU time of the calling thread (what the tick loop
pays), the CPU of the helpers (feeder thread and child process, or the SDK's threads), the wall time until the
file is complete, and the file's size. The messages are handed over already encoded (the arm state too: the
recorder's writer-process path hands the arm state as numbers and the child encodes it, so the first row is
slightly pessimistic for the parent). Nothing here is a bt_grasp log afterwards: foxglove-sdk sets neither
``publish_time`` nor ``sequence`` and writes its own header and metadata, which is why the comparison is
about cost only.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


@dataclass(frozen=True)
class Message:
    channel: int  # the source file's channel id
    log_time: int
    data: bytes


@dataclass(frozen=True)
class Source:
    schemas: dict[int, tuple[str, str, bytes]]  # id -> (name, encoding, data)
    channels: dict[int, tuple[str, str, int]]  # id -> (topic, message encoding, schema id)
    ticks: list[list[Message]]


def read_source(path: Path, max_ticks: int | None) -> Source:
    from mcap.reader import make_reader

    schemas: dict[int, tuple[str, str, bytes]] = {}
    channels: dict[int, tuple[str, str, int]] = {}
    ticks: list[list[Message]] = [[]]
    with path.open("rb") as stream:
        for schema, channel, message in make_reader(stream).iter_messages(log_time_order=False):
            if schema is not None and schema.id not in schemas:
                schemas[schema.id] = (schema.name, schema.encoding, bytes(schema.data))
            channels.setdefault(channel.id, (channel.topic, channel.message_encoding, channel.schema_id))
            if channel.topic == "/bt/tick" and ticks[-1]:
                if max_ticks is not None and len(ticks) >= max_ticks:
                    break
                ticks.append([])
            ticks[-1].append(Message(channel.id, message.log_time, bytes(message.data)))
    return Source(schemas, channels, ticks)


def _child_cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def write_process(source: Source, path: Path) -> dict[str, float]:
    from bt_grasp.recording import writer_process

    writer_process.prestart()  # as an episode does, before its world is built: not part of the run
    time.sleep(1.0)  # let the child's interpreter start-up and imports end before the clocks start
    child = writer_process._idle[-1].process.pid
    child_cpu0, process0, wall0 = _child_cpu_s(child), time.process_time(), time.perf_counter()
    thread0 = time.thread_time()
    writer = writer_process.ProcessWriter(str(path), chunk_size=4 * 1024 * 1024, compression="zstd", arm_state=None)
    writer.start(profile="", library="bench")
    ids = {sid: writer.register_schema(*spec) for sid, spec in source.schemas.items()}
    chans = {cid: writer.register_channel(topic, enc, ids.get(sid, 0))
             for cid, (topic, enc, sid) in source.channels.items()}
    for tick in source.ticks:
        for m in tick:
            writer.add_message(chans[m.channel], m.log_time, m.data, m.log_time)
        writer.flush()
    caller = time.thread_time() - thread0
    writer.finish(fsync=False)
    wall = time.perf_counter() - wall0
    helpers = (time.process_time() - process0 - caller) + (_child_cpu_s(child) - child_cpu0)
    return {"caller_cpu_s": caller, "helper_cpu_s": helpers, "wall_s": wall}


def write_mcap(source: Source, path: Path) -> dict[str, float]:
    from mcap.writer import CompressionType, Writer

    process0, wall0, thread0 = time.process_time(), time.perf_counter(), time.thread_time()
    with path.open("wb") as stream:
        writer = Writer(stream, chunk_size=4 * 1024 * 1024, compression=CompressionType.ZSTD)
        writer.start(profile="", library="bench")
        ids = {sid: writer.register_schema(*spec) for sid, spec in source.schemas.items()}
        chans = {cid: writer.register_channel(topic, enc, ids.get(sid, 0))
                 for cid, (topic, enc, sid) in source.channels.items()}
        for tick in source.ticks:
            for m in tick:
                writer.add_message(chans[m.channel], log_time=m.log_time, data=m.data, publish_time=m.log_time)
            writer.flush()
        caller = time.thread_time() - thread0
        writer.finish()
    wall = time.perf_counter() - wall0
    return {"caller_cpu_s": caller, "helper_cpu_s": time.process_time() - process0 - caller, "wall_s": wall}


def _write_foxglove(source: Source, path: Path, threads: int | None, flush: bool = True) -> dict[str, float]:
    import foxglove
    from foxglove.mcap import MCAPWriteOptions

    process0, wall0, thread0 = time.process_time(), time.perf_counter(), time.thread_time()
    context = foxglove.Context()
    options = MCAPWriteOptions(chunk_size=4 * 1024 * 1024, compression_threads=threads)
    writer = foxglove.open_mcap(path, allow_overwrite=True, context=context, writer_options=options)
    chans = {}
    for cid, (topic, enc, sid) in source.channels.items():
        schema = foxglove.Schema(name=source.schemas[sid][0], encoding=source.schemas[sid][1],
                                 data=source.schemas[sid][2]) if sid in source.schemas else None
        chans[cid] = foxglove.Channel(topic, schema=schema, message_encoding=enc, context=context)
    for tick in source.ticks:
        for m in tick:
            chans[m.channel].log(m.data, log_time=m.log_time)
        if flush:
            writer.flush()
    caller = time.thread_time() - thread0
    writer.close()
    wall = time.perf_counter() - wall0
    return {"caller_cpu_s": caller, "helper_cpu_s": time.process_time() - process0 - caller, "wall_s": wall}


WRITERS: dict[str, Callable[[Source, Path], dict[str, float]]] = {
    "writer process": write_process,
    "mcap in-process": write_mcap,
    "foxglove-sdk": lambda s, p: _write_foxglove(s, p, 0),
    "foxglove-sdk, zstd on 1 thread": lambda s, p: _write_foxglove(s, p, 1),
    "foxglove-sdk, 4 MiB chunks (no tick flush)": lambda s, p: _write_foxglove(s, p, 0, flush=False),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("log", type=Path, help="a bt_grasp log whose messages are written again")
    parser.add_argument("--reps", type=int, default=3)
    parser.add_argument("--ticks", type=int, default=None, help="only the first N ticks of the log")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    if not args.log.is_file():
        raise SystemExit(f"bench_mcap_writers: error: {args.log}: no such log file")
    source = read_source(args.log, args.ticks)
    n_messages = sum(len(t) for t in source.ticks)
    runs: dict[str, list[dict[str, float]]] = {name: [] for name in WRITERS}
    with tempfile.TemporaryDirectory() as tmp:
        for rep in range(args.reps):
            for name, write in WRITERS.items():
                out = Path(tmp) / f"{rep}.mcap"
                got = write(source, out)
                got["mb"] = out.stat().st_size / 1e6
                out.unlink()
                runs[name].append(got)
    ticks = len(source.ticks)
    rows: dict[str, Any] = {}
    for name, figures in runs.items():
        med = {k: statistics.median(f[k] for f in figures) for k in figures[0]}
        rows[name] = {"caller_us_per_tick": round(1e6 * med["caller_cpu_s"] / ticks, 1),
                      "helper_us_per_tick": round(1e6 * med["helper_cpu_s"] / ticks, 1),
                      "wall_s": round(med["wall_s"], 3), "mb": round(med["mb"], 2)}
    report = {"log": str(args.log), "ticks": ticks, "messages": n_messages, "reps": args.reps,
              "load_average": [round(x, 2) for x in os.getloadavg()], "cpus": os.cpu_count(), "writers": rows}
    if args.json:
        print(json.dumps(report))
        return
    print(f"{args.log}: {ticks} ticks, {n_messages} messages; medians of {args.reps} interleaved rounds; "
          f"load {report['load_average']}")
    print(f"{'writer':44s} {'tick loop us/tick':>18s} {'helpers us/tick':>16s} {'wall s':>8s} {'MB':>7s}")
    for name, r in rows.items():
        print(f"{name:44s} {r['caller_us_per_tick']:18.1f} {r['helper_us_per_tick']:16.1f} {r['wall_s']:8.3f} "
              f"{r['mb']:7.2f}")


if __name__ == "__main__":
    main()
