"""A run's MCAP file written by a child process, so the tick loop only hands data over.

:class:`ProcessWriter` offers the calls of ``mcap.writer.Writer`` that :class:`RunRecorder` makes, plus
``add_arm_state``: the arm state of a tick as plain numbers, which the child turns into ``/robot/joint_state``
and ``/tf`` with the same :class:`ArmStateEncoder` the recorder uses in-process (the same bytes), and
``add_encoded``: any message given by its inputs (the tick's JSON, a trajectory, an image), which the child
encodes with ``encodings.encode``, as the recorder would (the same bytes). So the tick loop's thread neither
encodes JSON nor compresses images. Calls are batched in the parent; at every ``flush()`` (the recorder's
tick boundary) the batch is pickled (arrays of 64 KiB or more out of band, not copied: pickle protocol 5) and
handed to a feeder thread that writes it to the child's stdin while the tick loop goes on. The child
(``python -m bt_grasp.recording.writer_process``: a fresh interpreter, so nothing of a renderer's threads is
forked and no caller's ``__main__`` is imported again) owns the file: it writes each batch and ends a chunk at
each flush, and at ``finish()`` writes the summary, fsyncs, closes and says "ok"; then it waits for the next
file, so a process that records many episodes (benchmarks, evaluation workers, a resident runner) starts the
child once, and ``prestart()`` starts it ahead of a run, while the world is built (its interpreter start-up and
imports cost ~0.4 s of CPU: paid during the run, they slowed a pick's tick loop). If the parent dies without
finishing (SIGKILL), the child reads its stdin to the end and finishes the file: the log keeps every batch
written to the pipe before the kill. The child ignores SIGINT and SIGTERM (a Ctrl-C reaches the whole process
group; the parent decides when to finish).

Schema and channel ids follow ``mcap.writer.Writer``'s rule (1, 2, ... in registration order) in both
processes, so the parent names channels without waiting for the child.
"""

from __future__ import annotations

import atexit
import contextlib
import logging
import os
import pickle
import queue
import selectors
import signal
import struct
import subprocess
import sys
import tempfile
import threading
from collections.abc import Mapping
from typing import BinaryIO, Literal, TextIO, TypeAlias, TypedDict

import numpy as np
from numpy.typing import NDArray

from bt_grasp.recording.arm_state import ArmStateEncoder
from bt_grasp.recording.encodings import Encoding, encode

log = logging.getLogger(__name__)

#: how long ``finish`` waits for the child to write the summary and exit
FINISH_TIMEOUT_S = 120.0


class ArmSettings(TypedDict):
    """What the child's :class:`ArmStateEncoder` is built from (``robot_model``: build the default one)."""

    joint_names: list[str]
    base_frame: str
    tool_frame: str
    robot_model: bool


class FileSettings(TypedDict):
    """The file a batch opens (``("open", settings)``)."""

    path: str
    chunk_size: int
    compression: str
    arm_state: ArmSettings | None


Statics: TypeAlias = dict[tuple[str, str], NDArray[np.float64]]
#: the requests a batch carries, one tuple each, the request's kind first (``write_file`` carries them out)
_Item: TypeAlias = (
    tuple[Literal["m"], int, int, bytes, int, int]  # channel, log time, data, publish time, sequence
    | tuple[Literal["e"], int, int, int, str, tuple[object, ...]]  # channel, log time, sequence, encoding, args
    | tuple[Literal["arm"], tuple[int, int], tuple[int, int], int, int | None, dict[str, object]]
    | tuple[Literal["flush"]]
    | tuple[Literal["fsync"]]
    | tuple[Literal["statics"], Statics]
    | tuple[Literal["open"], FileSettings]
    | tuple[Literal["start"], str, str]  # profile, library
    | tuple[Literal["metadata"], str, dict[str, str]]
    | tuple[Literal["attachment"], int, int, str, str, bytes]
    | tuple[Literal["schema"], int, str, str, bytes]  # id, name, encoding, data
    | tuple[Literal["channel"], int, str, str, int]  # id, topic, message encoding, schema id
    | tuple[Literal["finish"], bool]  # fsync
)
#: a batch on the pipe: the pickle's size and how many out-of-band buffers follow it, then each buffer's size
_FRAME = struct.Struct("<QI")
_BUFFER_SIZE = struct.Struct("<Q")
#: arrays at least this large (images, depth) travel beside the pickle, not copied into it (pickle protocol 5)
OUT_OF_BAND_BYTES = 64 * 1024
_Send = tuple[bytes, list[pickle.PickleBuffer]]


class WriterProcessError(RuntimeError):
    """The writer process failed (its message says why) or did not finish in time."""


class _Child:
    """One writer process. It writes one file at a time and, once a file is finished and reported "ok", waits
    for the next: a process that records many episodes starts (and imports) it once."""

    def __init__(self) -> None:
        # read only to say why it failed: unlike a pipe nobody reads, it never fills and stalls the child
        self.stderr = tempfile.TemporaryFile()  # noqa: SIM115 (closed in close(): it lives as long as the child)
        self.owner = os.getpid()
        self.process = subprocess.Popen([sys.executable, "-m", "bt_grasp.recording.writer_process"],
                                        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self.stderr)

    def alive(self) -> bool:
        """Running, and this process's own (a forked process must not share another's pipes)."""
        return self.owner == os.getpid() and self.process.poll() is None

    def reply(self, timeout_s: float) -> str | None:
        """The child's next line ("ok" or its failure), or None if it said nothing in time."""
        stdout = self.process.stdout
        assert stdout is not None
        with selectors.DefaultSelector() as selector:
            selector.register(stdout, selectors.EVENT_READ)
            if not selector.select(timeout_s):
                return None
        return stdout.readline().decode(errors="replace").strip()

    def stderr_tail(self) -> str:
        self.stderr.seek(0)
        return self.stderr.read().decode(errors="replace").strip()[-500:]

    def close(self, timeout_s: float = 5.0) -> None:
        """End the process: its input ends, it exits (finishing a file it still held)."""
        with contextlib.suppress(OSError):
            if self.process.stdin is not None:
                self.process.stdin.close()
        try:
            self.process.wait(timeout_s)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        for stream in (self.process.stdout, self.stderr):
            if stream is not None:
                stream.close()


_idle: list[_Child] = []
_idle_lock = threading.Lock()


def _drop_dead() -> None:
    """Forget (and close the pipes of) idle children that ended; the caller holds ``_idle_lock``."""
    for child in [c for c in _idle if not c.alive()]:
        _idle.remove(child)
        if child.owner == os.getpid():
            child.close()


def prestart() -> None:
    """Start a writer process now unless one is waiting already, so that the next :class:`ProcessWriter` finds
    it ready: its interpreter's start-up and imports overlap whatever the caller does next (building a world)
    instead of the run."""
    with _idle_lock:
        _drop_dead()
        if not _idle:
            _idle.append(_Child())


def _take_child() -> _Child:
    with _idle_lock:
        _drop_dead()
        if _idle:
            return _idle.pop()
    return _Child()


@atexit.register
def _close_idle() -> None:
    with _idle_lock:
        children, _idle[:] = list(_idle), []
    for child in children:
        if child.owner == os.getpid():
            child.close()


class ProcessWriter:
    """``mcap.writer.Writer``'s calls, carried out by a writer process that owns ``path`` until ``finish()``."""

    def __init__(self, path: str, *, chunk_size: int, compression: str, arm_state: ArmSettings | None) -> None:
        """``compression``: "zstd", "lz4" or "none"; ``arm_state``: the :class:`ArmStateEncoder`'s settings
        (``joint_names``, ``base_frame``, ``tool_frame``, ``robot_model``: True builds the default robot model
        in the child) or None when no arm state is handed over."""
        with open(path, "wb"):  # a path that cannot be written fails here, before the run, not at its end
            pass
        settings: FileSettings = {"path": str(path), "chunk_size": int(chunk_size), "compression": compression,
                                  "arm_state": ArmSettings(**arm_state) if arm_state is not None else None}
        self._child = _take_child()
        self._process = self._child.process
        self._pending: queue.SimpleQueue[_Send | None] = queue.SimpleQueue()
        self._feeder = threading.Thread(target=self._feed, name="log-writer-feeder", daemon=True)
        self._feeder.start()
        self._batch: list[_Item] = [("open", settings)]
        self._schemas = 0
        self._channels = 0
        self._finished = False
        self._broken: str | None = None

    # -- mcap.writer.Writer's calls ---------------------------------------------------------------------

    def start(self, profile: str = "", library: str = "") -> None:
        self._batch.append(("start", profile, library))

    def add_metadata(self, name: str, data: Mapping[str, str]) -> None:
        self._batch.append(("metadata", name, dict(data)))

    def add_attachment(self, create_time: int, log_time: int, name: str, media_type: str, data: bytes) -> None:
        self._batch.append(("attachment", create_time, log_time, name, media_type, bytes(data)))

    def register_schema(self, name: str, encoding: str, data: bytes) -> int:
        self._schemas += 1
        self._batch.append(("schema", self._schemas, name, encoding, bytes(data)))
        return self._schemas

    def register_channel(self, topic: str, message_encoding: str, schema_id: int) -> int:
        self._channels += 1
        self._batch.append(("channel", self._channels, topic, message_encoding, schema_id))
        return self._channels

    def add_message(self, channel_id: int, log_time: int, data: bytes, publish_time: int, sequence: int = 0) -> None:
        self._batch.append(("m", channel_id, log_time, data, publish_time, sequence))

    def add_encoded(self, channel_id: int, log_time: int, sequence: int, encoding: Encoding,
                    args: tuple[object, ...]) -> None:
        """A message the child encodes (``encodings.encode(encoding, args)``: the same bytes as in this
        process) and writes on ``channel_id`` at ``log_time``. ``args`` must not change until the next
        ``flush()`` (they are pickled then): pass copies of arrays a caller may write to."""
        self._batch.append(("e", channel_id, log_time, sequence, encoding.value, args))

    def flush(self, fsync: bool = False) -> None:
        """Send what was added since the last flush; the child writes it and ends the chunk (then fsyncs)."""
        self._batch.append(("flush",))
        if fsync:
            self._batch.append(("fsync",))
        self._send()

    def finish(self, fsync: bool = True) -> None:
        """Send the rest, let the child write the summary and footer (and fsync), and wait for its word; the
        child then waits for the next file."""
        if self._finished:
            return
        self._finished = True
        self._batch.append(("finish", fsync))
        self._send()
        self._pending.put(None)  # the feeder stops after the last batch
        self._feeder.join(FINISH_TIMEOUT_S)
        said = self._child.reply(FINISH_TIMEOUT_S)
        if said == "ok":
            with _idle_lock:
                _idle.append(self._child)
            return
        if said is None and self._child.alive():
            self._child.process.kill()
            self._child.close()
            raise WriterProcessError(f"the log writer did not finish within {FINISH_TIMEOUT_S:g} s")
        self._child.close()
        why = said or self._child.stderr_tail() or self._broken or "no word"
        raise WriterProcessError(f"the log writer failed (exit {self._process.returncode}): {why}")

    # -- the arm state -----------------------------------------------------------------------------------

    def add_arm_state(self, channels: tuple[int, int], sequences: tuple[int, int], log_time: int, tick: int | None,
                      robot: Mapping[str, object]) -> None:
        """The child encodes ``robot`` (``ArmStateEncoder.encode``) and writes the joint state and /tf messages
        on ``channels`` with ``sequences`` at ``log_time``."""
        self._batch.append(("arm", channels, sequences, log_time, tick, dict(robot)))

    def set_statics(self, statics: Mapping[tuple[str, str], NDArray[np.float64]]) -> None:
        """The static transforms every later arm state's /tf repeats."""
        self._batch.append(("statics", {k: np.array(v, dtype=np.float64) for k, v in statics.items()}))

    # -- the hand-over ------------------------------------------------------------------------------------

    def _send(self) -> None:
        batch, self._batch = self._batch, []
        buffers: list[pickle.PickleBuffer] = []

        def out_of_band(buffer: pickle.PickleBuffer) -> bool:  # True: in the pickle; False: beside it
            if buffer.raw().nbytes < OUT_OF_BAND_BYTES:
                return True
            buffers.append(buffer)
            return False

        self._pending.put((pickle.dumps(batch, protocol=5, buffer_callback=out_of_band), buffers))

    def _feed(self) -> None:
        """Write each pickled batch to the child's stdin, in order, until the last one (the pipe stays open for
        the child's next file)."""
        stdin = self._process.stdin
        assert stdin is not None
        while True:
            sent = self._pending.get()
            if sent is None:
                break
            if self._broken is not None:
                continue
            data, buffers = sent
            raws = [buffer.raw() for buffer in buffers]
            try:
                stdin.write(_FRAME.pack(len(data), len(raws)))
                for raw in raws:
                    stdin.write(_BUFFER_SIZE.pack(raw.nbytes))
                stdin.write(data)
                for raw in raws:
                    stdin.write(raw)
                stdin.flush()
            except OSError as exc:  # the child died: finish() reports it
                self._broken = f"the pipe to the log writer broke: {exc}"


def _read_batch(stream: BinaryIO) -> list[_Item] | None:
    """The next whole batch on ``stream``, or None at its end (a batch cut short by a dead parent is dropped)."""
    head = stream.read(_FRAME.size)
    if len(head) < _FRAME.size:
        return None
    size, count = _FRAME.unpack(head)
    sizes = []
    for _ in range(count):
        field = stream.read(_BUFFER_SIZE.size)
        if len(field) < _BUFFER_SIZE.size:
            return None
        sizes.append(_BUFFER_SIZE.unpack(field)[0])
    data = stream.read(size)
    if len(data) < size:
        return None
    buffers = []
    for length in sizes:
        buffer = stream.read(length)
        if len(buffer) < length:
            return None
        buffers.append(buffer)
    batch: list[_Item] = pickle.loads(data, buffers=buffers)
    return batch


def _encoder(settings: FileSettings) -> ArmStateEncoder | None:
    arm = settings.get("arm_state")
    if arm is None:
        return None
    model = None
    if arm.get("robot_model", False):
        # deferred: start-up time (pinocchio and the robot's meshes, only for a log with the robot model)
        from bt_grasp.recording.robot_model import default_robot_model

        model = default_robot_model()  # built once per process: its later files reuse it
    return ArmStateEncoder(arm["joint_names"], arm["base_frame"], arm["tool_frame"], robot_model=model)


def write_file(first: list[_Item], requests: BinaryIO) -> bool:
    """Write one file: ``first`` is the batch that opens it (``("open", settings)`` first), the rest comes from
    ``requests`` until "finish" (True) or the input's end (False: the parent died; the file is finished with
    the batches that came whole)."""
    from mcap.writer import CompressionType, Writer

    opening = first[0]
    if opening[0] != "open":
        raise ValueError(f"a file must begin with 'open', not {opening[0]!r}")
    settings = opening[1]
    kinds = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}
    encoder = _encoder(settings)
    statics: Statics = {}
    batch: list[_Item] | None = first[1:]
    with open(settings["path"], "wb") as stream:
        writer = Writer(stream, chunk_size=int(settings["chunk_size"]), compression=kinds[settings["compression"]])
        while True:
            if batch is None:  # the parent died without finishing: finish the file with what came whole
                writer.finish()
                return False
            for item in batch:
                if item[0] == "m":
                    writer.add_message(item[1], log_time=item[2], data=item[3], publish_time=item[4], sequence=item[5])
                elif item[0] == "e":
                    data = encode(Encoding(item[4]), item[5])  # ValueError for a value no Encoding has
                    writer.add_message(item[1], log_time=item[2], data=data, publish_time=item[2], sequence=item[3])
                elif item[0] == "arm":
                    if encoder is None:
                        raise ValueError("an arm state, but no arm-state settings")
                    (js_channel, tf_channel), (js_seq, tf_seq), t, tick, robot = item[1:]
                    joint_state, tf = encoder.encode(t, tick, robot, statics)
                    writer.add_message(js_channel, log_time=t, data=joint_state, publish_time=t, sequence=js_seq)
                    if tf is not None:
                        writer.add_message(tf_channel, log_time=t, data=tf, publish_time=t, sequence=tf_seq)
                elif item[0] == "flush":
                    writer.flush()
                elif item[0] == "statics":
                    statics = item[1]
                elif item[0] == "fsync":
                    stream.flush()
                    os.fsync(stream.fileno())
                elif item[0] == "start":
                    writer.start(profile=item[1], library=item[2])
                elif item[0] == "metadata":
                    writer.add_metadata(item[1], item[2])
                elif item[0] == "attachment":
                    writer.add_attachment(item[1], item[2], item[3], item[4], item[5])
                elif item[0] == "schema":
                    got = writer.register_schema(name=item[2], encoding=item[3], data=item[4])
                    if got != item[1]:
                        raise ValueError(f"schema id {got}, the parent named it {item[1]}")
                elif item[0] == "channel":
                    got = writer.register_channel(item[2], item[3], item[4])
                    if got != item[1]:
                        raise ValueError(f"channel id {got}, the parent named it {item[1]}")
                elif item[0] == "finish":
                    writer.finish()
                    stream.flush()
                    if item[1]:
                        os.fsync(stream.fileno())
                    return True
                else:
                    raise ValueError(f"unknown request {item[0]!r}")
            batch = _read_batch(requests)


def serve(requests: BinaryIO, replies: TextIO) -> None:
    """The child: write file after file, saying "ok" after each, until the input ends."""
    while True:
        first = _read_batch(requests)
        if first is None or not write_file(first, requests):
            return
        print("ok", file=replies, flush=True)


def main() -> int:
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    try:
        serve(sys.stdin.buffer, sys.stdout)
    except Exception as exc:  # the parent raises it at finish()
        print(f"{type(exc).__name__}: {exc}", flush=True)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
