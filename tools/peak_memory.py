"""Peak memory of a command and of each process it starts (issue 27): evaluation workers, the log writer.

    python tools/peak_memory.py [--interval 0.1] [--json] -- COMMAND [ARGS...]

Runs COMMAND and, every ``--interval`` seconds until it ends, reads ``/proc/PID/status`` of it and of every
process below it: the kernel's high-water mark of the resident size (``VmHWM``) and, whenever a process's
resident size is the highest seen so far, its ``/proc/PID/smaps_rollup`` (anonymous memory, file-backed pages,
how much of them is shared with other processes). Processes are grouped by role from their command line:
``main``, ``campaign worker`` (a spawned ``multiprocessing`` child), ``log writer``
(``bt_grasp.recording.writer_process``), ``other``. Prints per role the largest peak and the breakdown taken at
that process's highest sample; exits with COMMAND's exit code. Linux only (reads ``/proc``).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

ROLLUP_KEYS = ("Rss", "Pss", "Anonymous", "Shared_Clean", "Private_Clean", "Private_Dirty")


@dataclass
class Seen:
    pid: int
    role: str
    hwm_kib: int = 0
    rss_kib: int = 0
    rollup_kib: dict[str, int] = field(default_factory=dict)


def _children(pid: int) -> list[int]:
    kids: list[int] = []
    for task in Path(f"/proc/{pid}/task").glob("*"):
        try:
            kids += [int(p) for p in (task / "children").read_text().split()]
        except OSError:
            continue
    return kids


def _role(pid: int, root: int) -> str:
    if pid == root:
        return "main"
    try:
        cmd = Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return "other"
    if "bt_grasp.recording.writer_process" in cmd:
        return "log writer"
    if "multiprocessing" in cmd and ("spawn_main" in cmd or "forkserver" in cmd):
        return "campaign worker"
    return "other"


def _status_kib(pid: int) -> tuple[int, int]:
    values = {}
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        key, _, rest = line.partition(":")
        if key in ("VmHWM", "VmRSS"):
            values[key] = int(rest.split()[0])
    return values.get("VmHWM", 0), values.get("VmRSS", 0)


def _rollup_kib(pid: int) -> dict[str, int]:
    out = {}
    for line in Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines()[1:]:
        key, _, rest = line.partition(":")
        if key in ROLLUP_KEYS:
            out[key] = int(rest.split()[0])
    return out


def watch(command: list[str], interval_s: float) -> tuple[int, list[Seen]]:
    proc = subprocess.Popen(command)
    seen: dict[int, Seen] = {}
    while True:
        done = proc.poll() is not None
        stack, pids = [proc.pid], []
        while stack and not done:
            pid = stack.pop()
            pids.append(pid)
            stack += _children(pid)
        for pid in pids:
            try:
                hwm, rss = _status_kib(pid)
                entry = seen.setdefault(pid, Seen(pid, _role(pid, proc.pid)))
                entry.hwm_kib = max(entry.hwm_kib, hwm)
                if rss > entry.rss_kib:
                    entry.rss_kib = rss
                    entry.rollup_kib = _rollup_kib(pid)
            except (OSError, ValueError, IndexError):
                continue  # it ended between the listing and the read
        if done:
            return proc.returncode, list(seen.values())
        time.sleep(interval_s)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--interval", type=float, default=0.1)
    parser.add_argument("--json", action="store_true")
    parser.add_argument("command", nargs=argparse.REMAINDER)
    args = parser.parse_args()
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("no command given")
    code, seen = watch(command, args.interval)
    roles: dict[str, dict[str, object]] = {}
    for role in ("main", "campaign worker", "log writer", "other"):
        group = [s for s in seen if s.role == role]
        if not group:
            continue
        top = max(group, key=lambda s: s.hwm_kib)
        roles[role] = {"processes": len(group), "peak_mib": round(top.hwm_kib / 1024, 1),
                       "at_highest_sample_mib": {k: round(v / 1024, 1) for k, v in top.rollup_kib.items()}}
    report = {"command": command, "exit_code": code, "load_average": [round(x, 2) for x in os.getloadavg()],
              "roles": roles}
    if args.json:
        print(json.dumps(report), file=sys.stderr)
    else:
        for role, r in roles.items():
            parts = ", ".join(f"{k} {v}" for k, v in r["at_highest_sample_mib"].items())  # type: ignore[attr-defined]
            print(f"peak memory: {role} ({r['processes']} process(es)): {r['peak_mib']} MiB peak; at its highest "
                  f"sample (MiB): {parts}", file=sys.stderr)
    return code


if __name__ == "__main__":
    raise SystemExit(main())
