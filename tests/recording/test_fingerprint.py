"""The run fingerprint: a log and a live run of the same ticks agree; a difference names its first tick."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bt_grasp.recording import RunRecorder
from bt_grasp.recording.fingerprint import Fingerprint, FingerprintRecorder, fingerprint_of_log
from bt_grasp.recording.reader import open_log

POSES = {"box": np.eye(4).tolist()}


@dataclass(frozen=True)
class Grasp:
    T: np.ndarray
    score: float


def _ticks(reason_at_3: str = "COLLISION", q_bump: float = 0.0) -> list[tuple[Any, ...]]:
    """Five ticks of a two-node tree: the leaf runs, fails at tick 3 with a reason, is retried, succeeds."""
    out = []
    for tick in range(1, 6):
        leaf = ("RUNNING", None)
        if tick == 3:
            leaf = ("FAILURE", reason_at_3)
        elif tick == 5:
            leaf = ("SUCCESS", None)
        nodes = [
            {"uid": 1, "path": "root", "status": "RUNNING" if tick < 5 else "SUCCESS", "failure_reason": None,
             "feedback": f"wall {tick * 0.37:.2f} s"},  # a feedback sentence is not part of the fingerprint
            {"uid": 2, "path": "root/Approach", "status": leaf[0], "failure_reason": leaf[1], "feedback": ""},
        ]
        board = {"grasp": Grasp(np.eye(4) * tick, 0.5), "skip": tick // 3, "cloud": np.zeros((100, 3))}
        q = np.array([0.1, -1.9, 1.9, -1.57, -1.57, 0.0]) + 0.01 * tick
        if tick == 4:
            q[3] += q_bump
        robot = {"q_rad": q.tolist(), "qd_rad_s": [0.0] * 6, "gripper_width_m": 0.085 - 0.001 * tick,
                 "T_base_tcp": np.eye(4).tolist()}
        out.append((tick, tick * 10_000_000, nodes, board, robot))
    return out


def _live(ticks: list[tuple[Any, ...]]) -> Fingerprint:
    recorder = FingerprintRecorder()
    for tick in ticks:
        recorder.write_tick(*tick)
    return recorder.finish(POSES)


def test_a_log_and_the_live_run_have_the_same_fingerprint(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    with RunRecorder(path, metadata={"seed": "1"}) as recorder:
        for tick in _ticks():
            recorder.write_tick(*tick)
        recorder.write_result(60_000_000, {"success": True, "judge": {"object_poses": POSES}})
    from_log = fingerprint_of_log(open_log(path))
    live = _live(_ticks())
    assert len(from_log.ticks) == 5
    assert from_log.digest == live.digest
    assert from_log.first_difference(live) is None
    assert live.ticks[2].nodes[1] == (2, "FAILURE", "COLLISION")


def test_a_different_failure_reason_is_found_at_its_tick() -> None:
    difference = _live(_ticks()).first_difference(_live(_ticks(reason_at_3="PLAN_FAILED")))
    assert difference is not None and difference.tick == 3
    assert difference.what == ("node 2 (root/Approach): FAILURE/COLLISION vs FAILURE/PLAN_FAILED",)


def test_joints_compare_to_a_micro_radian() -> None:
    base = _live(_ticks())
    assert base.digest == _live(_ticks(q_bump=1e-8)).digest  # well inside one 1e-6 rad step
    moved = base.first_difference(_live(_ticks(q_bump=3e-6)))
    assert moved is not None and moved.tick == 4 and moved.what[0].startswith("joint 3:")


def test_final_poses_and_run_length_count() -> None:
    ticks = _ticks()
    a = _live(ticks)
    recorder = FingerprintRecorder()
    for tick in ticks:
        recorder.write_tick(*tick)
    T = np.eye(4)
    T[0, 3] = 1e-5
    moved = recorder.finish({"box": T})
    difference = a.first_difference(moved)
    assert difference is not None and difference.tick is None and difference.what == ("final pose of box",)
    shorter = _live(ticks[:4])
    difference = a.first_difference(shorter)
    assert difference is not None and difference.tick == 5 and "run length" in difference.what[0]
    assert a.first_difference(shorter, compare_final=False) is None


def test_a_ticks_digest_is_the_sha256_of_its_canonical_text_with_or_without_the_blackboards_text() -> None:
    # issue 27: the blackboard's canonical text is kept by the recorder (not re-encoded every tick); the digest
    # must stay what it was: sha256 of _canonical([tick, nodes, blackboard, q, gripper]), addresses removed
    import hashlib

    from bt_grasp.recording.fingerprint import TickPrint, _canonical

    board = (("grasp", '{"x":"<Thing at 0x7f12ab>","y":[1.5,"nan"]}'), ("quote", 'say "hi" at 0xZ \u00e9'))
    nodes = ((1, "RUNNING", None), (2, "FAILURE", "NO_DETECTION at 0xdeadbeef"))
    for q, gripper in (((1, -2, 3, 4, 5, 6), 850), (None, None)):
        want = hashlib.sha256(_canonical([7, nodes, board, q, gripper]).encode()).hexdigest()
        assert TickPrint(7, nodes, board, q, gripper).digest == want
        assert TickPrint(7, nodes, board, q, gripper, _canonical(board)).digest == want
        assert TickPrint(7, nodes, board, q, gripper) == TickPrint(7, nodes, board, q, gripper, _canonical(board))
