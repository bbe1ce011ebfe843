"""Seeded fuzzing of what users open and what reaches bt_grasp from outside: every surface of :data:`SURFACES`.

Every case must be answered by exit 0 (the damage was harmless) or exit 2 with one sentence on stderr that
names the file: never a traceback, never another exit code, never a hang (a per-case alarm of
:data:`CASE_TIMEOUT_S`), never a worker over :data:`CASE_MEMORY_BYTES` resident (its kernel high-water mark, reset
before each case; an address-space limit stops a runaway), never a file written outside the case's own folder, and
never a read of the job's trap (a file outside every case's folder that hostile names point at:
``tools/fuzz_surfaces.py``). Cases run in a worker process that is restarted when it dies.

    python tools/fuzz_inputs.py --cases 2000 --seed 0          # prints the counts; exit 1 if any case failed

Log mutations: bytes (truncated, bit-flipped, zeroed, inserted, spliced), records (a top-level record
duplicated, chunks re-ordered, a length field set huge) and contents (the seed log re-written with the mcap
library, so well-formed MCAP, with one bt_grasp message of the wrong shape, the wrong encoding, or messages
duplicated and re-ordered). Issue 42's surfaces (files a mesh names, URDF trees, collision-cache entries, ONNX
models, control messages, resident requests, crafted ``--resim`` logs) are in ``tools/fuzz_surfaces.py``.
`tests/test_fuzz_inputs.py` runs a bounded number of cases in the suite.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import random
import re
import resource
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))  # its sibling tools/fuzz_surfaces.py
import fuzz_surfaces  # noqa: E402

SEED_LOG = REPO / "tests" / "data" / "old_logs" / "format1.mcap"
#: each case's bounds (issue 42): its time, and the worker's resident memory (kernel high-water mark)
CASE_TIMEOUT_S = 10
CASE_MEMORY_BYTES = 2 << 30
#: the address space past which a worker's allocation fails (a safety stop; the renderer reserves ~2.4 GB)
MEMORY_LIMIT = 6 << 30
MAGIC = b"\x89MCAP0\r\n"

LOG_KINDS = ("truncate", "flip", "ff_window", "zero", "insert", "splice", "duplicate_record", "reorder_chunks",
             "huge_length", "wrong_schema", "wrong_encoding", "rechunk", "hostile_strings")
RESULTS_KINDS = ("type", "drop", "cut", "binary", "huge", "deep", "markup", "not_object", "nan", "encoding")
LOG_VIEWS = ("summary", "json", "failures", "tick", "export_frames", "report", "topic", "leaf", "btlog", "foxglove")

#: every surface the suite fuzzes, and the surfaces other work is adding now: a row each, filled (its kinds and its
#: ``make``/``run`` functions, as in tools/fuzz_surfaces.py) when its code lands on this branch
SURFACES: dict[str, tuple[str, ...] | None] = {
    "log": LOG_KINDS,  # `replay LOG` and its views
    "results": RESULTS_KINDS,  # `eval report`
    "mesh": fuzz_surfaces.MESH_KINDS,  # `scene validate`: a mesh and the files it names
    "urdf": fuzz_surfaces.URDF_KINDS,  # `scene validate`: a URDF object's link tree
    "cache": fuzz_surfaces.CACHE_KINDS,  # the collision-shape cache's entries and folder
    "model": fuzz_surfaces.MODEL_KINDS,  # `detector check`: an ONNX model
    "control": fuzz_surfaces.CONTROL_KINDS,  # Foxglove parameters and /control/command messages
    "resident": fuzz_surfaces.RESIDENT_KINDS,  # frames and requests to the resident process
    "resim": fuzz_surfaces.RESIM_KINDS,  # `replay LOG --resim` of a crafted log
    "camera_recording": None,  # a RealSense recording (.db3) read back (the hardware work: not on this branch yet)
    "cell_file": None,  # a hardware cell file (the hardware work)
    "twin_socket": None,  # the controller twin's sockets (RTDE, dashboard, gripper: the twin work)
}

GOOD_ROW: dict[str, Any] = {
    "campaign": "fuzz", "episode": "e0", "tree": "trees/pick.xml", "scene": "tabletop", "seed": 0,
    "fault_plan": "none", "params": {"color": "red"}, "success": False, "failure_reason": "NO_DETECTION",
    "failed_leaf": "Perceive", "ticks": 700, "sim_time_s": 7.0, "episode_wall_s": 1.2,
    "retries": {"Perceive": 1}, "retries_total": 1, "mcap": None,
    "environment": {"id": "abc", "cpu_model": "x", "cpu_count": 2, "python": "3.11", "libraries": {}},
}
#: values a hostile writer puts where bt_grasp expects something else
HOSTILE_VALUES: tuple[Any, ...] = ("x", "5", "", [], [1, "a"], {}, {"uid": "a"}, None, 1.5, -1, True, 10**30, -(10**30),
                                   1e308, float("nan"), "\udcff", "<b>[/]$x$</b>")


# ---------------------------------------------------------------- MCAP structure (byte level)
def top_records(data: bytes) -> list[tuple[int, int, int]]:
    """(offset, opcode, total length) of each top-level record after the magic, as far as they parse."""
    out, pos = [], len(MAGIC)
    while pos + 9 <= len(data):
        opcode, length = struct.unpack_from("<BQ", data, pos)
        end = pos + 9 + length
        if end > len(data):
            break
        out.append((pos, opcode, end - pos))
        pos = end
    return out


def _records_mutation(data: bytes, kind: str, rng: random.Random) -> bytes:
    records = top_records(data)
    if kind == "duplicate_record":
        off, _, length = rng.choice(records)
        return data[: off + length] + data[off: off + length] + data[off + length:]
    if kind == "reorder_chunks":  # two chunks swap places: the index's offsets now point at the wrong ones
        chunks = [r for r in records if r[1] == 0x06]
        a, b = sorted(rng.sample(chunks, 2), key=lambda r: r[0])
        return (data[: a[0]] + data[b[0]: b[0] + b[2]] + data[a[0] + a[2]: b[0]] + data[a[0]: a[0] + a[2]]
                + data[b[0] + b[2]:])
    # huge_length: a record's length field, or a chunk's declared sizes, set huge
    buf = bytearray(data)
    off, opcode, _ = rng.choice(records)
    huge = rng.choice([2**63 - 1, 2**64 - 1, 2**40, 2**32, len(data) * 1000])
    field_at = off + 1
    if opcode == 0x06 and rng.random() < 0.5:  # a chunk: start, end, uncompressed size, crc, ... records length
        field_at = off + 9 + rng.choice([16, 28 + 4 + 4])  # uncompressed size, or the records' byte length
    struct.pack_into("<Q", buf, field_at, huge)
    return bytes(buf)


def _bytes_mutation(data: bytes, kind: str, rng: random.Random) -> bytes:
    buf = bytearray(data)
    if kind == "truncate":
        return bytes(buf[: rng.randrange(len(buf))])
    if kind == "flip":
        for _ in range(rng.randint(1, 20)):
            i = rng.randrange(len(buf))
            buf[i] ^= 1 << rng.randrange(8)
    elif kind == "ff_window":  # eight bytes of 0xff somewhere: any length field there becomes huge
        i = rng.randrange(len(buf) - 8)
        buf[i: i + 8] = b"\xff" * 8
    elif kind == "zero":
        i = rng.randrange(len(buf))
        n = min(rng.randint(1, 512), len(buf) - i)
        buf[i: i + n] = bytes(n)
    elif kind == "insert":
        i = rng.randrange(len(buf))
        buf[i:i] = rng.randbytes(rng.randint(1, 256))
    else:  # splice: the head of the file joined to a later tail
        i = rng.randrange(len(buf))
        buf = buf[:i] + buf[rng.randrange(len(buf)):]
    return bytes(buf)


# ---------------------------------------------------------------- MCAP contents (re-written with the mcap library)
@dataclass
class Corpus:
    """The seed log, raw and as records the mcap writer can write again."""

    raw: bytes
    metadata: list[tuple[str, dict[str, str]]] = field(default_factory=list)
    attachments: list[tuple[str, bytes]] = field(default_factory=list)
    schemas: dict[int, tuple[str, str, bytes]] = field(default_factory=dict)  # id -> name, encoding, data
    channels: dict[int, tuple[str, str, int]] = field(default_factory=dict)  # id -> topic, encoding, schema id
    messages: list[tuple[int, int, int, bytes]] = field(default_factory=list)  # channel, log, publish, data


def load_corpus(path: Path = SEED_LOG) -> Corpus:
    from mcap.reader import make_reader

    corpus = Corpus(path.read_bytes())
    reader = make_reader(io.BytesIO(corpus.raw))
    corpus.metadata = [(m.name, dict(m.metadata)) for m in reader.iter_metadata()]
    corpus.attachments = [(a.name, a.data) for a in reader.iter_attachments()]
    for schema, channel, message in reader.iter_messages():
        if schema is not None:
            corpus.schemas[schema.id] = (schema.name, schema.encoding, schema.data)
        corpus.channels[channel.id] = (channel.topic, channel.message_encoding, channel.schema_id)
        corpus.messages.append((channel.id, message.log_time, message.publish_time, message.data))
    return corpus


def _hostile_value(rng: random.Random) -> Any:
    if rng.random() < 0.1:  # deep nesting (recursion in whoever walks it): a placeholder `dumps` expands
        return f"__DEEP_{rng.choice([150, 900, 3000, 20000])}__"
    return rng.choice(HOSTILE_VALUES)


def dumps(value: Any) -> bytes:
    """JSON as a hostile writer would write it: NaN allowed, lone surrogates kept as bytes, and each deep
    placeholder replaced by tree nodes nested that deep."""
    text = json.dumps(value, allow_nan=True)  # ensure_ascii: a lone surrogate stays an escape, "\\udcff"

    def deep(match: re.Match[str]) -> str:
        n = int(match.group(1))
        return '{"uid": 99, "name": "d", "children": [' * n + '{"uid": 98}' + "]}" * n

    return re.sub(r'"__DEEP_(\d+)__"', deep, text).encode("utf-8", "surrogateescape")


def _poke(value: Any, rng: random.Random) -> Any:
    """``value`` with one place in it (a key, an item, the whole) replaced by something hostile or removed."""
    if isinstance(value, dict) and value and rng.random() < 0.85:
        key = rng.choice(sorted(value))
        out = dict(value)
        roll = rng.random()
        if roll < 0.25:
            out.pop(key)
        elif roll < 0.6:
            out[key] = _hostile_value(rng)
        else:
            out[key] = _poke(value[key], rng)
        return out
    if isinstance(value, list) and value and rng.random() < 0.85:
        out_list = list(value)
        i = rng.randrange(len(out_list))
        out_list[i] = _poke(out_list[i], rng) if rng.random() < 0.6 else _hostile_value(rng)
        return out_list
    return _hostile_value(rng)


#: the shapes named in issue 22: a tick number that is a string, a tree without structure, ...
TARGETED: tuple[tuple[str, str, Any], ...] = (
    ("/bt/tick", "tick", "5"), ("/bt/tick", "stamp_ns", "late"), ("/bt/tick", "nodes", {"uid": 1}),
    ("/bt/tick", "nodes", [{"status": "SUCCESS"}]), ("/bt/tick", "bb", [1, 2]), ("/bt/tick", "bb_removed", 7),
    ("/bt/tree", "structure", None), ("/bt/tree", "structure", []), ("/bt/tree", "tick", "x"),
    ("/bt/tree", "structure", {"uid": "root", "children": 3}), ("/run/result", "success", "yes"),
    ("/run/result", "wall_time_s", "fast"), ("/robot/joint_state", "position", "x"),
    ("/robot/joint_state", "position", [[1.0]]), ("/motion/trajectory", "q_rad", 5),
    ("/faults", "tick", [1]), ("/bt/events", "tick", {}),
)


#: strings a hostile writer puts in names, reasons and values: Rich markup, HTML, mathtext, path steps, control
#: and bidirectional characters, XML-illegal characters, a very long one
HOSTILE_STRINGS: tuple[str, ...] = ("[/]", "[link=https://x.invalid]x[/link]", "<script>alert(1)</script>", "$x^$",
                                    "$\\frac{", "../../x", "/etc/passwd", "a\nb\rc", "\x00\x01\x1b[31m", "\u202e",
                                    "\ufffe", "%s%n{0}", "x" * 100_000, "", " ", "\\", '"\'<>&')


def _taint(value: Any, rng: random.Random, keep: float) -> Any:
    """Every string in ``value`` (keys of objects too, now and then) with a hostile string added or put in its
    place; ``keep``: the chance a string stays as it was (structure such as statuses is then mostly kept)."""
    if isinstance(value, str):
        if rng.random() < keep:
            return value
        hostile = rng.choice(HOSTILE_STRINGS)
        return hostile if rng.random() < 0.3 else value + hostile
    if isinstance(value, list):
        return [_taint(v, rng, keep) for v in value]
    if isinstance(value, dict):
        return {(_taint(k, rng, keep) if rng.random() < 0.1 else k): _taint(v, rng, keep) for k, v in value.items()}
    return value


def _mutate_contents(corpus: Corpus, kind: str, rng: random.Random) -> bytes:
    from mcap.writer import CompressionType, Writer

    channels = dict(corpus.channels)
    messages = list(corpus.messages)
    metadata = [(name, dict(values)) for name, values in corpus.metadata]
    json_at = [i for i, m in enumerate(messages) if channels[m[0]][1] == "json"]
    if kind == "wrong_schema":
        if rng.random() < 0.35:
            topic, key, value = rng.choice(TARGETED)
            chosen = [i for i in json_at if channels[messages[i][0]][0] == topic]
            i = rng.choice(chosen)
            msg = json.loads(messages[i][3])
            if value is None and rng.random() < 0.5:
                msg.pop(key, None)
            else:
                msg[key] = value
        else:
            i = rng.choice(json_at)
            msg = _poke(json.loads(messages[i][3]), rng)
        messages[i] = (*messages[i][:3], dumps(msg))
    elif kind == "wrong_encoding":
        roll = rng.random()
        if roll < 0.4:  # a channel says it is not json (or json where protobuf was)
            cid = rng.choice(sorted(channels))
            topic, _, schema_id = channels[cid]
            channels[cid] = (topic, rng.choice(["cbor", "ros1", "protobuf", "json", ""]), schema_id)
        elif roll < 0.8:  # a message that is not UTF-8 (latin-1 text, or raw bytes)
            i = rng.choice(json_at)
            data = messages[i][3]
            bad = (data.decode().replace('"', '"\xe9', 1).encode("latin-1") if rng.random() < 0.5
                   else rng.randbytes(rng.randint(0, 64)))
            messages[i] = (*messages[i][:3], bad)
        else:  # metadata that says something else than a bt_grasp reader expects
            name, values = metadata[0]
            values[rng.choice(["log_format", "time_origin_ns", "seed", "tree_file"])] = rng.choice(
                ["", "x", "3", "-1", "1e400", "\u202e", "9" * 400])
            metadata[0] = (name, values)
    elif kind == "hostile_strings":  # well-formed messages whose strings are hostile: names, reasons, values
        keep = rng.choice([0.0, 0.5, 0.9])
        for i in json_at:
            if rng.random() < 0.7:
                messages[i] = (*messages[i][:3], dumps(_taint(json.loads(messages[i][3]), rng, keep)))
        name, values = metadata[0]
        metadata[0] = (name, {k: (_taint(v, rng, keep) if k not in ("log_format", "time_origin_ns") else v)
                              for k, v in values.items()})
    else:  # rechunk: messages duplicated, re-ordered, written in chunks of another size
        for _ in range(rng.randint(1, 6)):
            i = rng.randrange(len(messages))
            messages.insert(rng.randrange(len(messages) + 1), messages[i])
        if rng.random() < 0.5:
            rng.shuffle(messages)
    out = io.BytesIO()
    compression = rng.choice([CompressionType.ZSTD, CompressionType.NONE, CompressionType.LZ4])
    writer = Writer(out, chunk_size=rng.choice([64, 1024, 1 << 20]), compression=compression)
    writer.start(profile="", library="bt_grasp fuzz")
    sids = {sid: writer.register_schema(name, encoding, data)
            for sid, (name, encoding, data) in sorted(corpus.schemas.items())}
    ids = {cid: writer.register_channel(topic, encoding, sids.get(schema_id, 0))
           for cid, (topic, encoding, schema_id) in sorted(channels.items())}
    for cid, log_time, publish_time, data in messages:
        writer.add_message(ids[cid], log_time, data, publish_time)
    for name, values in metadata:
        writer.add_metadata(name, values)
    for name, data in corpus.attachments:
        writer.add_attachment(0, 0, name, "application/octet-stream", data)
    writer.finish()
    return out.getvalue()


def mutate_log(corpus: Corpus, rng: random.Random, kind: str | None = None) -> tuple[str, bytes]:
    kind = kind or rng.choice(LOG_KINDS)
    if kind in ("duplicate_record", "reorder_chunks", "huge_length"):
        return kind, _records_mutation(corpus.raw, kind, rng)
    if kind in ("wrong_schema", "wrong_encoding", "rechunk", "hostile_strings"):
        return kind, _mutate_contents(corpus, kind, rng)
    return kind, _bytes_mutation(corpus.raw, kind, rng)


def mutate_results(rng: random.Random, kind: str | None = None) -> tuple[str, bytes]:
    rows = []
    for n in range(rng.randint(1, 6)):
        row = json.loads(json.dumps(GOOD_ROW))
        row["episode"], row["seed"] = f"e{n}", n
        rows.append(row)
    victim = rng.choice(rows)
    kind = kind or rng.choice(RESULTS_KINDS)
    key = rng.choice(sorted(GOOD_ROW))
    if kind == "type":
        victim[key] = _hostile_value(rng)
    elif kind == "drop":
        victim.pop(key)
    elif kind == "markup":
        victim[key] = rng.choice(["[/]", "$\\frac{1}{0$", "<script>x</script>", "[link=x]y", "\x00", "\u202e"])
    lines = [dumps(r) for r in rows]
    if kind == "cut":
        i = rng.randrange(len(lines))
        lines[i] = lines[i][: rng.randrange(len(lines[i]))]
    elif kind == "binary":
        lines.insert(rng.randrange(len(lines) + 1), rng.randbytes(rng.randint(1, 64)))
    elif kind == "huge":
        lines.append(rng.choice([b'{"episode": "h", "seed": 1e400, "ticks": ' + b"9" * 5000 + b"}",
                                 json.dumps({**GOOD_ROW, "seed": 10**30, "ticks": -(10**30)}).encode(),
                                 json.dumps({**GOOD_ROW, "sim_time_s": 1e308, "retries_total": 10**12}).encode()]))
    elif kind == "deep":
        lines.append(b"[" * 100_000 + b"]" * 100_000)
    elif kind == "not_object":
        lines.append(rng.choice([b"[]", b"1", b'"s"', b"null"]))
    elif kind == "nan":
        lines.append(json.dumps({**GOOD_ROW, "episode": "n", rng.choice(["sim_time_s", "episode_wall_s", "seed",
                                                                          "retries_total"]): float("nan")}).encode())
    elif kind == "encoding":
        i = rng.randrange(len(lines))
        lines[i] = lines[i].replace(b'"fuzz"', b'"f\xe9\xff"') if rng.random() < 0.5 else lines[i].decode().encode(
            "utf-16")
    return kind, b"\n".join(lines) + rng.choice([b"\n", b""])


# ---------------------------------------------------------------- running one case (in the worker)
def _run_case(args: list[str]) -> tuple[int, str]:
    from bt_grasp.cli.main import main

    if args and args[0] in fuzz_surfaces.RUNNERS:  # a surface that is not a command: answered as one
        try:
            return fuzz_surfaces.RUNNERS[args[0]](*args[1:])
        except BaseException as exc:  # what the case is for: a crash must be seen, not hidden
            import traceback

            return -1, "Traceback: " + "".join(traceback.format_exception_only(type(exc), exc)).strip()
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(args)
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
        except BaseException as exc:  # what the case is for: a crash must be seen, not hidden
            import traceback

            return -1, "Traceback: " + "".join(traceback.format_exception_only(type(exc), exc)).strip()
    return code, err.getvalue()


def _worker() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    # no logging set-up: Python's last-resort handler writes warnings to the (redirected) stderr, as in a real run
    def on_alarm(_signum: int, _frame: object) -> None:
        raise TimeoutError("case took too long")

    signal.signal(signal.SIGALRM, on_alarm)
    try:
        for line in sys.stdin:
            args = json.loads(line)
            signal.alarm(CASE_TIMEOUT_S)
            try:
                code, err = _run_case(args)
            except TimeoutError as exc:  # raised by the alarm between two of a runner's own steps
                code, err = -1, f"Traceback: {exc}"
            finally:
                signal.alarm(0)
            print(json.dumps({"code": code, "stderr": err[-2000:]}), flush=True)
    finally:
        fuzz_surfaces.stop_resident()


@dataclass
class Verdict:
    ok: bool
    detail: str


def judge(code: int, stderr: str, file_name: str | tuple[str, ...], *, notices: bool = False,
          ran: bool = False) -> Verdict:
    """Exit 0, or exit 2 with one line of stderr naming the file (any of ``file_name``); anything else is a
    failure. ``notices``: lines a scene's loader says before (``object '...': ...``) may precede the refusal;
    ``ran``: exit 1 is an answer too (a re-simulation that did not reproduce its log)."""
    names = (file_name,) if isinstance(file_name, str) else file_name
    lines = [line for line in stderr.splitlines() if line.strip()]
    if "Traceback" in stderr or code == -1:
        return Verdict(False, f"crash: {stderr.strip()[-300:]}")
    if code == 0 or (ran and code == 1):
        return Verdict(True, "read")
    said = [line for line in lines if not (notices and line.startswith("object '"))]
    if code == 2 and len(said) == 1 and any(name in said[0] for name in names):
        return Verdict(True, "refused")
    return Verdict(False, f"exit {code} with {len(lines)} lines: {stderr.strip()[-300:]}")


class Runner:
    def __init__(self, cwd: Path, tmp: Path, own: Path | None = None) -> None:
        self.proc: subprocess.Popen[str] | None = None
        self.cwd, self.tmp = cwd, tmp
        self.own = own or tmp.parent  # the worker's own cache and resident folders live here

    def _start(self) -> subprocess.Popen[str]:
        env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""),
                   TMPDIR=str(self.tmp), MPLBACKEND="Agg", BT_GRASP_CACHE_DIR=str(self.own / "cache"),
                   BT_GRASP_RESIDENT_DIR=str(self.own / "resident"),
                   BT_GRASP_DECOMPOSITION_LIMIT_S="3")  # a damaged mesh can need CoACD: past 3 s one sentence

        return subprocess.Popen([sys.executable, str(Path(__file__).resolve()), "--worker"], stdin=subprocess.PIPE,
                                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=env, cwd=self.cwd)

    def run(self, args: list[str], file_name: str | tuple[str, ...], *, notices: bool = False,
            ran: bool = False) -> Verdict:
        if self.proc is None or self.proc.poll() is not None:
            self.proc = self._start()
        assert self.proc.stdin is not None and self.proc.stdout is not None
        with contextlib.suppress(OSError):  # the kernel's high-water mark of the worker, from this case on
            Path(f"/proc/{self.proc.pid}/clear_refs").write_text("5")
        self.proc.stdin.write(json.dumps(args) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            code = self._end()
            return Verdict(False, f"the worker died (signal or memory): {code}")
        peak = _peak_bytes(self.proc.pid)
        answer = json.loads(line)
        verdict = judge(int(answer["code"]), str(answer["stderr"]), file_name, notices=notices, ran=ran)
        if verdict.ok and peak > CASE_MEMORY_BYTES:
            return Verdict(False, f"the worker's memory reached {peak >> 20} MiB")
        return verdict

    def _end(self) -> int:
        """Close the worker's pipes (it leaves when its input ends) and wait for it; its exit code."""
        assert self.proc is not None
        for pipe in (self.proc.stdin, self.proc.stdout):
            if pipe is not None:
                with contextlib.suppress(OSError):  # a dead worker's pipe may refuse the flush
                    pipe.close()
        code = self.proc.wait(timeout=60)
        self.proc = None
        return code

    def close(self) -> None:
        if self.proc is not None:
            self._end()


def _peak_bytes(pid: int) -> int:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return 0


@dataclass(frozen=True)
class Case:
    name: str
    kind: str  # "<surface>:<mutation>"
    view: str
    file: Path
    args: list[str]
    names: tuple[str, ...] = ()  # what a refusal may name (the case's folder, a device it was given)
    notices: bool = False
    ran: bool = False


#: case i is of kind KINDS[i % len(KINDS)]: any run of len(KINDS) cases exercises every kind once
KINDS = tuple(f"{surface}:{k}" for surface, kinds in SURFACES.items() if kinds for k in kinds)


def make_case(i: int, seed: int, folder: Path, corpus: Corpus, trap: dict[str, Path] | None = None) -> Case:
    """Case ``i`` of ``seed``: its input file written into ``folder`` (its own, empty), and its command line.
    The kind and the view go round (every kind and view in few cases); the damage itself is drawn."""
    rng = random.Random(seed * 1_000_003 + i)
    family, kind = KINDS[i % len(KINDS)].split(":")
    if family in fuzz_surfaces.MAKERS:
        assert trap is not None
        args = fuzz_surfaces.MAKERS[family][1](kind, rng, folder, trap)
        view = {"resim": "replay --resim", "model": "detector check", "cache": "collision shapes",
                "control": "foxglove control", "resident": "resident"}.get(family, "scene validate")
        return Case(f"{family} {i}", f"{family}:{kind}", view, folder, args, (str(folder), "/dev/zero"),
                    notices=family in ("mesh", "urdf", "resim"), ran=family == "resim")
    if family == "log":
        kind, data = mutate_log(corpus, rng, kind)
        path = folder / f"case{i}.mcap"
        path.write_bytes(data)
        view = LOG_VIEWS[i % len(LOG_VIEWS)]  # len(KINDS) and len(LOG_VIEWS) share no factor: every pair occurs
        extra = {"summary": [], "json": ["--json"], "failures": ["--failures"],
                 "tick": ["--tick", str(rng.randint(0, 8))],
                 "export_frames": ["--export-frames", str(folder / "frames")],
                 "report": ["--report", str(folder / "report.html")],
                 "topic": ["--topic", rng.choice(["/bt/tick", "/camera/depth", "/tf", "/robot/joint_state"])],
                 "leaf": ["--leaf", rng.choice(["Grasp", "Detect", "Pick", *HOSTILE_STRINGS[:8]])],
                 "btlog": ["--export-btlog", str(folder / "run.btlog")],
                 "foxglove": ["--foxglove", "--layout-out", str(folder / "layout.json")]}[view]
        return Case(f"log {i}", f"log:{kind}", view, path, ["replay", str(path), *extra])
    kind, data = mutate_results(rng, kind)
    path = folder / f"case{i}.jsonl"
    path.write_bytes(data)
    return Case(f"results {i}", f"results:{kind}", "eval report", path,
                ["eval", "report", str(path), "--out", str(folder / "report.html")])


def _listing(root: Path, skip: Path, own: tuple[Path, ...] = ()) -> set[tuple[str, int]]:
    """Every file and folder under ``root`` except ``skip`` (the running case's own folder) and ``own`` (the
    worker's collision cache and resident folder: bt_grasp's own, written by design), with sizes."""
    out = set()
    for dirpath, dirnames, filenames in os.walk(root):
        here = Path(dirpath)
        if here == skip or here in own:
            dirnames[:] = []
            continue
        for name in filenames + dirnames:
            p = here / name
            out.add((str(p), p.stat().st_size if p.is_file() else -1))
    return out


@dataclass
class Outcome:
    counts: Counter[str] = field(default_factory=Counter)
    kinds: Counter[str] = field(default_factory=Counter)
    views: Counter[str] = field(default_factory=Counter)
    failures: list[str] = field(default_factory=list)
    seconds: float = 0.0


def _fuzz_part(indices: range, seed: int, corpus: Corpus, root: Path) -> Outcome:
    """Run the cases ``indices`` of ``seed`` in one worker. Each runs in its own folder; the worker's working
    folder and TMPDIR are watched folders that must stay as they were, and so must the rest of ``root``."""
    outcome = Outcome()
    cwd, worker_tmp, cases_dir = root / "cwd", root / "tmp", root / "cases"
    for folder in (cwd, worker_tmp, cases_dir):
        folder.mkdir(parents=True)
    own = (root / "cache", root / "resident")
    for folder in own:
        folder.mkdir(mode=0o700)
    (cwd / "sentinel.txt").write_text("must not change\n")
    trap = fuzz_surfaces.make_trap(root / "trap")
    runner = Runner(cwd, worker_tmp, root)
    try:
        for i in indices:
            folder = cases_dir / f"case{i}"
            folder.mkdir()
            case = make_case(i, seed, folder, corpus, trap)
            before = _listing(root, folder, own)
            verdict = runner.run(case.args, case.names or case.file.name, notices=case.notices, ran=case.ran)
            after = _listing(root, folder, own)
            if verdict.ok and after != before:
                changed = sorted(p for p, _ in after ^ before)
                verdict = Verdict(False, f"wrote outside its folder: {changed[:3]}")
            if verdict.ok and fuzz_surfaces.trap_was_read(trap):
                verdict = Verdict(False, f"read {trap['secret']}, outside its folder")
            if fuzz_surfaces.trap_was_read(trap):
                os.utime(trap["secret"], (0, time.time()))
            outcome.kinds[case.kind] += 1
            outcome.views[case.view] += 1
            if verdict.ok:
                outcome.counts[verdict.detail] += 1
            else:
                outcome.counts["failed"] += 1
                outcome.failures.append(f"{case.name} [{case.kind}, {case.view}] {' '.join(case.args[:2])}: "
                                        f"{verdict.detail}")
                for leftover in worker_tmp.iterdir():  # so one leak is reported once, not by every later case
                    shutil.rmtree(leftover) if leftover.is_dir() else leftover.unlink()
            _remove(folder)
            done = sum(outcome.kinds.values())
            if done % 100 == 0:  # a long run under load shows where it is, and whether anything failed yet
                print(f"{root.name}: {done} cases, {outcome.counts['failed']} failed", file=sys.stderr, flush=True)
    finally:
        runner.close()
        _end_resident(root / "resident")
    return outcome


def _end_resident(folder: Path) -> None:
    """A worker that died leaves its resident running (its own session): end it by the pid its lock records."""
    with contextlib.suppress(OSError, ValueError):
        pid = int((folder / "resident.lock").read_text().strip())
        if b"bt_grasp.resident.server" in Path(f"/proc/{pid}/cmdline").read_bytes():
            os.kill(pid, signal.SIGKILL)


def _remove(folder: Path) -> None:
    """A case's folder, whatever a case left in it (a folder others may write: made writable again to go)."""
    for dirpath, dirnames, _ in os.walk(folder):
        for name in dirnames:
            with contextlib.suppress(OSError):
                if not os.path.islink(os.path.join(dirpath, name)):
                    os.chmod(os.path.join(dirpath, name), 0o700)
    shutil.rmtree(folder, ignore_errors=True)


def fuzz(n: int, seed: int, jobs: int = 1) -> Outcome:
    """Run cases 0..n-1 of ``seed`` in ``jobs`` workers (each with its own watched folders); the cases and
    their verdicts do not depend on ``jobs``."""
    from concurrent.futures import ThreadPoolExecutor

    start = time.monotonic()
    corpus = load_corpus()
    with tempfile.TemporaryDirectory(prefix="bt_grasp_fuzz_") as tmp, ThreadPoolExecutor(max_workers=jobs) as pool:
        parts = list(pool.map(lambda j: _fuzz_part(range(j, n, jobs), seed, corpus, Path(tmp) / f"job{j}"),
                              range(jobs)))
    outcome = Outcome()
    for part in parts:
        outcome.counts.update(part.counts)
        outcome.kinds.update(part.kinds)
        outcome.views.update(part.views)
        outcome.failures.extend(part.failures)
    outcome.failures.sort(key=lambda line: int(line.split()[1]))
    outcome.seconds = time.monotonic() - start
    return outcome


def main() -> int:
    parser = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    parser.add_argument("--cases", type=int, default=2000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=1, help="workers run at once (the cases are the same)")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        _worker()
        return 0
    outcome = fuzz(args.cases, args.seed, args.jobs)
    for line in outcome.failures[:50]:
        print("FAIL", line)
    print(f"{args.cases} cases, seed {args.seed}: {outcome.counts['read']} read, {outcome.counts['refused']} refused "
          f"in one sentence, {outcome.counts['failed']} failed, in {outcome.seconds:.0f} s ({args.jobs} workers)")
    print("surfaces:", ", ".join(f"{surface} {sum(v for k, v in outcome.kinds.items() if k.startswith(surface + ':'))}"
                                 for surface, kinds in SURFACES.items() if kinds),
          "(not yet on this branch: " + ", ".join(s for s, k in SURFACES.items() if not k) + ")")
    print("mutations:", ", ".join(f"{k} {v}" for k, v in sorted(outcome.kinds.items())))
    print("views:", ", ".join(f"{k} {v}" for k, v in sorted(outcome.views.items())))
    return 1 if outcome.failures else 0


if __name__ == "__main__":
    raise SystemExit(main())
