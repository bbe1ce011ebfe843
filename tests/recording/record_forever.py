"""Child process for the crash tests: records ticks until killed, printing each flushed tick number.

Usage: python record_forever.py OUT.mcap [--sleep-s S] [--max-ticks N]
"""

from __future__ import annotations

import argparse
import signal
import sys
import time

import numpy as np

from bt_grasp.recording import RunRecorder


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("out")
    parser.add_argument("--sleep-s", type=float, default=0.002)
    parser.add_argument("--max-ticks", type=int, default=1_000_000)
    args = parser.parse_args()
    # A job started in the background by a non-interactive shell inherits SIGINT ignored (and Python then keeps
    # it so); the test is about a user's Ctrl-C, which reaches a process with the default handler.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    names = ["Root", "Detect", "Grasp"]
    with RunRecorder(args.out, metadata={"seed": "3", "tree_file": "kill.xml"}) as rec:
        rec.write_tree_structure(0, {"uid": 1, "type": "Sequence", "name": "Root", "path": "Root",
                                     "kind": "control", "attributes": {}, "children": []})
        for tick in range(args.max_ticks):
            nodes = [{"uid": i + 1, "path": n, "type": n, "name": n, "status": "RUNNING",
                      "feedback": f"tick {tick}", "failure_reason": None, "ticked": True}
                     for i, n in enumerate(names)]
            robot = {"q_rad": np.full(6, 0.001 * tick), "qd_rad_s": np.zeros(6), "gripper_width_m": 0.05,
                     "T_base_tcp": np.eye(4)}
            rec.write_tick(tick, tick * 10_000_000, nodes, {"tick": tick}, robot)
            if tick % 20 == 0:
                rec.write_color_image(tick * 10_000_000, np.full((48, 64, 3), tick % 255, np.uint8), "cam")
            rec.flush_tick()
            sys.stdout.write(f"{tick}\n")
            sys.stdout.flush()
            time.sleep(args.sleep_s)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
