"""Same seed, same run, across a code change: record the shipped tasks' logs, then compare two sets of them.

    python tools/same_runs.py record OUT [--seeds 0,1,2] [--task pick ...] [--jobs 2] [--checkout DIR]
    python tools/same_runs.py compare BEFORE AFTER

``record`` runs ``bt-grasp run trees/T.xml --scene scenes/T.yaml --seed S --log OUT/T-S.mcap`` for every shipped
task (``bt_grasp.bench.tasks.TASKS``) with ``SOURCE_DATE_EPOCH`` set, from the checkout this file is in (its
``bt_grasp`` first on the path, the command line recorded as ``bt-grasp run ...`` whatever folder it runs from),
so two checkouts of different commits write comparable logs (``--checkout DIR``: run that checkout's code
instead of this one's, with this interpreter). ``compare`` reads every log of BEFORE and its
namesake in AFTER and reports, per log: whether every message (topic, log time, publish time, sequence, bytes)
is the same, per topic where not; whether the attachments and the metadata are the same apart from the commit
(``git_commit``); and whether the files' bytes are the same apart from the commit's characters and the data
section's checksum, which covers them. Exit 0 when every log is the same in all of that, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EPOCH = "1700000000"
SCRATCH = Path(tempfile.gettempdir()) / "bt_grasp_same_runs"
#: metadata that names the code, not the run
CODE_KEYS = ("git_commit",)


def _launch(args: list[str]) -> list[str]:
    code = ("import sys; sys.argv = ['bt-grasp', *sys.argv[1:]]; "
            "from bt_grasp.cli.main import main; main()")
    return [sys.executable, "-c", code, *args]


def record(out: Path, seeds: list[int], tasks: list[str], jobs: int, root: Path = ROOT) -> int:
    sys.path.insert(0, str(root))
    try:
        from bt_grasp.bench.tasks import TASKS
    except ImportError:  # a checkout from before bt_grasp/bench/
        from bt_grasp.tasks import TASKS  # type: ignore[no-redef]

    chosen = [t for t in TASKS if not tasks or t.name in tasks]
    out.mkdir(parents=True, exist_ok=True)
    SCRATCH.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "SOURCE_DATE_EPOCH": EPOCH, "PYTHONPATH": str(root)}

    def one(job: tuple[str, Path, Path, int, int]) -> str:
        name, tree, scene, max_ticks, seed = job
        log = SCRATCH / f"{name}-{seed}.mcap"  # one path for every checkout: the result names its log
        args = ["run", str(tree), "--scene", str(scene), "--seed", str(seed), "--log", str(log), "--quiet",
                "--max-ticks", str(max_ticks)]
        proc = subprocess.run(_launch(args), cwd=root, env=env, capture_output=True, text=True, check=False)
        if log.exists():
            shutil.move(log, out / log.name)
        return f"{name} seed {seed}: exit {proc.returncode}"

    todo = [(t.name, t.tree, t.scene, t.max_ticks, s) for t in chosen for s in seeds]
    with ThreadPoolExecutor(jobs) as pool:
        for line in pool.map(one, todo):
            print(line, flush=True)
    return 0


def _messages(path: Path) -> tuple[dict[str, list[tuple[int, int, int, bytes]]], dict[str, bytes], dict[str, str]]:
    from mcap.reader import make_reader

    topics: dict[str, list[tuple[int, int, int, bytes]]] = {}
    with path.open("rb") as f:
        reader = make_reader(f)
        for _schema, channel, message in reader.iter_messages(log_time_order=False):
            topics.setdefault(channel.topic, []).append(
                (message.log_time, message.publish_time, message.sequence, bytes(message.data)))
    with path.open("rb") as f:
        reader = make_reader(f)
        attachments = {a.name: bytes(a.data) for a in reader.iter_attachments()}
    with path.open("rb") as f:
        reader = make_reader(f)
        metadata = {f"{m.name}.{k}": v for m in reader.iter_metadata() for k, v in m.metadata.items()}
    return topics, attachments, metadata


def _bytes_apart_from_commit(a: Path, b: Path, meta_a: dict[str, str], meta_b: dict[str, str]) -> bool:
    """The files' bytes equal once each side's commit is replaced by the same text (the data section's CRC,
    which covers the metadata record, is left out of the comparison)."""
    da, db = a.read_bytes(), b.read_bytes()
    for key in CODE_KEYS:
        ca = next((v for k, v in meta_a.items() if k.endswith("." + key)), "")
        cb = next((v for k, v in meta_b.items() if k.endswith("." + key)), "")
        if ca and cb and len(ca) == len(cb):
            da, db = da.replace(ca.encode(), b"#" * len(ca)), db.replace(cb.encode(), b"#" * len(cb))
    if len(da) != len(db):
        return False
    differing = [i for i in range(len(da)) if da[i] != db[i]] if da != db else []
    if not differing:
        return True
    # the DataEnd record (opcode 0x0F, 4-byte CRC) is the only place left that may differ
    from mcap.records import DataEnd  # noqa: F401  (its layout: opcode, u64 length, u32 crc)

    end = da.rfind(b"\x0f\x04\x00\x00\x00\x00\x00\x00\x00")
    return end >= 0 and all(end + 9 <= i < end + 13 for i in differing)


def compare(before: Path, after: Path) -> int:
    logs = sorted(p.name for p in before.glob("*.mcap"))
    all_same = True
    report = []
    for name in logs:
        other = after / name
        if not other.exists():
            report.append({"log": name, "same": False, "why": "missing after"})
            all_same = False
            continue
        ta, aa, ma = _messages(before / name)
        tb, ab, mb = _messages(other)
        topics_differing = sorted(t for t in set(ta) | set(tb) if ta.get(t) != tb.get(t))
        meta_differing = sorted(k for k in set(ma) | set(mb)
                                if ma.get(k) != mb.get(k) and not k.endswith(tuple("." + c for c in CODE_KEYS)))
        attachments_same = aa == ab
        raw = _bytes_apart_from_commit(before / name, other, ma, mb)
        same = not topics_differing and not meta_differing and attachments_same and raw
        all_same &= same
        report.append({"log": name, "same": same, "messages": sum(len(v) for v in ta.values()),
                       "topics_differing": topics_differing, "metadata_differing": meta_differing,
                       "attachments_same": attachments_same, "bytes_same_apart_from_commit": raw})
    for row in report:
        print(json.dumps(row))
    print(f"{sum(r['same'] for r in report)}/{len(report)} logs the same")
    return 0 if all_same and report else 1


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="cmd", required=True)
    rec = sub.add_parser("record")
    rec.add_argument("out", type=Path)
    rec.add_argument("--seeds", default="0,1,2")
    rec.add_argument("--task", action="append", default=[])
    rec.add_argument("--jobs", type=int, default=2)
    rec.add_argument("--checkout", type=Path, default=ROOT)
    cmp_ = sub.add_parser("compare")
    cmp_.add_argument("before", type=Path)
    cmp_.add_argument("after", type=Path)
    args = parser.parse_args()
    if args.cmd == "record":
        return record(args.out.resolve(), [int(s) for s in args.seeds.split(",")], args.task, args.jobs,
                      args.checkout.resolve())
    return compare(args.before, args.after)


if __name__ == "__main__":
    raise SystemExit(main())
