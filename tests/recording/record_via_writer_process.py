"""Child process for the writer-process kill test: records ticks through the writer process (as ``bt-grasp run
--log`` does) until killed, and says on its stdout which ticks were flushed, outside the file.

"Flushed", for the writer process, means handed over whole: ``ProcessWriter.flush()`` queues the tick's batch, and
its feeder thread writes the batch (its lengths, the pickled batch, then its large arrays out of band) to the writer
process's stdin and flushes that pipe. Once that ``flush()`` of the pipe has returned, the batch is in the kernel's
pipe (or already read by the writer process), which outlives this process: the writer process reads its input to the
end and finishes the file. So this script watches the pipe itself: it wraps the idle writer process's stdin before
the recorder takes it, and after each completed ``flush()`` of the pipe prints ``flushed N`` for every tick N whose
arm state was in the bytes just handed over. A tick printed here is one the log must keep however the process dies.

Usage: python record_via_writer_process.py OUT.mcap [--max-ticks N]
Prints ``writer PID`` (the writer process) first.
"""

from __future__ import annotations

import argparse
import io
import sys
from typing import IO

import numpy as np

from bt_grasp.recording import writer_process
from bt_grasp.recording.robot_model import default_robot_model
from bt_grasp.recording.writer import RunRecorder


class ReportingPipe:
    """The writer process's stdin, reporting the ticks of each batch once the pipe's ``flush()`` returned."""

    def __init__(self, pipe: IO[bytes], report: IO[str]) -> None:
        self._pipe = pipe
        self._report = report
        self._pending = bytearray()

    def write(self, data: bytes) -> int:
        written = self._pipe.write(data)
        self._pending += data
        return written

    def flush(self) -> None:
        self._pipe.flush()  # returned: every byte written so far is in the kernel's pipe
        ticks: list[int] = []
        while True:  # every whole batch written so far, read as the writer process reads it
            stream = io.BytesIO(bytes(self._pending))
            batch = writer_process._read_batch(stream)
            if batch is None:
                break
            del self._pending[:stream.tell()]
            ticks += [int(item[4]) for item in batch if item[0] == "arm"]  # ("arm", channels, seqs, t, tick, robot)
        for tick in ticks:
            self._report.write(f"flushed {tick}\n")
        self._report.flush()

    def close(self) -> None:
        self._pipe.close()


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("out")
    parser.add_argument("--max-ticks", type=int, default=1_000_000)
    args = parser.parse_args()
    writer_process.prestart()
    child = writer_process._idle[-1]  # the one the recorder takes next
    assert child.process.stdin is not None
    child.process.stdin = ReportingPipe(child.process.stdin, sys.stdout)  # type: ignore[assignment]
    sys.stdout.write(f"writer {child.process.pid}\n")
    sys.stdout.flush()
    nodes = [{"uid": 1, "path": "Root", "type": "Sequence", "name": "Root", "kind": "Control", "status": "RUNNING",
              "feedback": "", "failure_reason": None, "ticked": True}]
    # the robot model puts every link on /tf: the writer process has real work per tick and lags behind
    with RunRecorder(args.out, metadata={"seed": "1"}, writer_process=True, handle_signals=False,
                     robot_model=default_robot_model()) as rec:
        for tick in range(1, args.max_ticks + 1):
            arm = {"q_rad": (np.linspace(-1.0, 1.0, 6) * (tick % 100) / 100.0).tolist(),
                   "qd_rad_s": [0.0] * 6, "gripper_width_m": 0.05}
            rec.write_tick(tick, tick * 10_000_000, nodes, {"tick": tick}, arm)
            rec.flush_tick()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
