"""Failure injection end to end: run a tree with a fault through ``bt_grasp.episode``, then read the
MCAP log to see that the fault fired (/faults), which reason the leaf reported (/bt/events), which
recovery branch ran next (/bt/tick) and whether the task still succeeded (/run/result).

One run per fault kind (~10-40 s each, so the module is marked ``slow``); the calibration is the eye-to-hand
one ``bt-grasp calibrate`` made for the default scene. Every check names the one leaf and the one reason the
fault's semantics (docs/faults.md) lead to on seed 3, and the branch that answers it.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "scenes" / "tabletop.yaml"
PICK = REPO / "trees" / "pick.xml"
RECOVERY = REPO / "trees" / "pick_with_recovery.xml"
SEED = 3
BLACKBOARD: dict[str, str | int | float] = {"color": "red", "lift_height": 0.15}

pytestmark = [pytest.mark.sim, pytest.mark.slow]


@pytest.fixture(scope="module")
def calibration() -> Path:
    """The eye-to-hand calibration of the default scene, made by `bt-grasp calibrate --scene
    scenes/tabletop.yaml --mount eye-to-hand --seed 0` (the calibrate command has its own tests)."""
    return REPO / "tests/data/calibration/tabletop_eye_to_hand.yaml"


@dataclass
class Outcome:
    summary: Any
    log: Any

    @property
    def faults(self) -> list[dict[str, Any]]:
        return self.log.faults

    def failures(self) -> list[dict[str, Any]]:
        """The leaves' failure events, in order: leaf, reason, tick, path."""
        return [e["payload"] for e in self.log.events if e.get("kind") == "failure"]

    def first_failure_after_fault(self) -> dict[str, Any]:
        """The first failure a leaf reported at or after the fault's tick: from /bt/events, or, when the tree
        recovered within the same tick (the event stream keeps only end-of-tick states), from the
        ``failed_leaf``/``failure_reason`` entries the leaf wrote to the recorded blackboard."""
        fault_tick = self.faults[0]["tick"]
        events = {f["tick"]: f for f in reversed(self.failures()) if f["reason"]}
        before = self.log.blackboard_at(fault_tick - 1) if fault_tick > 1 else {}
        last = (before.get("failed_leaf"), before.get("failure_reason"))
        for record in self.log.ticks:
            if record.tick < fault_tick:
                continue
            if record.tick in events:
                return events[record.tick]
            bb = self.log.blackboard_at(record.tick)
            now = (bb.get("failed_leaf"), bb.get("failure_reason"))
            if now != last and now[1] is not None:
                return {"tick": record.tick, "leaf": now[0], "reason": now[1], "source": "blackboard"}
            last = now
        raise AssertionError("no leaf reported a failure after the fault")

    def ran(self, node_name: str, after_tick: int = 0) -> bool:
        """Did a node of this name tick (and not fail) at or after a tick?"""
        uids = {uid for uid, info in self.log.nodes.items() if info.name == node_name}
        assert uids, f"no node named {node_name!r} in the log"
        return any(
            n.uid in uids and n.ticked and n.status in ("SUCCESS", "RUNNING")
            for t in self.log.ticks if t.tick >= after_tick
            for n in t.nodes
        )


def run(tmp_path: Path, calibration: Path, tree: Path, *inject: str) -> Outcome:
    from bt_grasp.episode import EpisodeRequest, run_episode
    from bt_grasp.recording.reader import open_log

    log_path = tmp_path / "run.mcap"
    request = EpisodeRequest(tree=tree, scene=SCENE, seed=SEED, calibration=calibration, log=log_path,
                             inject=tuple(inject), blackboard=dict(BLACKBOARD), max_ticks=6000)
    summary = run_episode(request)
    log = open_log(log_path)
    assert log.result is not None and log.result["success"] == summary.success
    assert log.result["faults_fired"] == len(log.faults) == summary.faults_fired
    assert log.metadata["inject"] == ";".join(inject)
    return Outcome(summary, log)


def fault_record(outcome: Outcome, kind: str) -> dict[str, Any]:
    assert outcome.faults, "the fault never fired"
    record = outcome.faults[0]
    assert record["fault"]["kind"] == kind
    return record


# --- recoverable faults: pick_with_recovery.xml still succeeds -------------------------------------------------


def test_frame_drop_is_recovered_by_looking_again(tmp_path: Path, calibration: Path) -> None:
    out = run(tmp_path, calibration, RECOVERY, "frame_drop@Perceive#1")
    record = fault_record(out, "frame_drop")
    assert record["fault"]["leaf"] == "Perceive"
    first = out.first_failure_after_fault()
    assert (first["leaf"], first["reason"]) == ("Perceive", "NO_FRAME")
    assert first["tick"] == record["tick"]
    assert out.ran("Sleep", first["tick"])  # the "anything else" branch: wait and look again
    assert out.summary.success, out.summary.to_json()


def test_planner_failure_in_every_candidate_tries_the_next_candidate(tmp_path: Path, calibration: Path) -> None:
    # PlanGrasp plans each candidate's approach (Approach executes that plan, it does not plan again), so a
    # planner that fails throughout PlanGrasp's attempt makes PlanGrasp fail PLAN_FAILED; the recovery skips
    # to the next candidate and the next attempt plans normally
    out = run(tmp_path, calibration, RECOVERY, "planner_fail@PlanGrasp#1:calls=1000,within_attempt=true")
    record = fault_record(out, "planner_fail")
    first = out.first_failure_after_fault()
    assert (first["leaf"], first["reason"]) == ("PlanGrasp", "PLAN_FAILED")
    assert first["tick"] >= record["tick"]  # one candidate per tick: it fails once all were tried
    assert out.ran("next_candidate", first["tick"])
    assert out.summary.success, out.summary.to_json()


def test_ik_failure_during_plan_grasp_tries_the_next_candidate(tmp_path: Path, calibration: Path) -> None:
    out = run(tmp_path, calibration, RECOVERY, "ik_fail@PlanGrasp#1:calls=1000,within_attempt=true")
    fault_record(out, "ik_fail")
    first = out.first_failure_after_fault()
    # no candidate has an IK solution: PlanGrasp says so by its typed reason (no longer read from a message)
    assert (first["leaf"], first["reason"]) == ("PlanGrasp", "IK_UNREACHABLE")
    assert out.ran("next_candidate_ik", first["tick"])
    assert out.summary.success, out.summary.to_json()


def test_object_nudged_after_perceive_empties_the_grasp_then_regrasps(tmp_path: Path, calibration: Path) -> None:
    # the 50 mm box slides 60 mm along x, the pads' width (the fingers close along y: a nudge along y puts the
    # box under a finger instead, see the next test and docs/faults.md), so it is no longer between the pads:
    # the descent is free and the fingers close on nothing
    out = run(tmp_path, calibration, RECOVERY, "nudge@PlanGrasp#1:dx_m=0.06,dy_m=0.0")
    record = fault_record(out, "object_nudge")
    assert record["fault"]["details"]["object"] == "red_box"
    first = out.first_failure_after_fault()
    assert (first["leaf"], first["reason"]) == ("Grasp", "GRASP_EMPTY")
    assert out.ran("regrasp", first["tick"])
    assert out.summary.success, out.summary.to_json()


def test_finger_landing_on_a_nudged_box_backs_off_before_opening(tmp_path: Path, calibration: Path) -> None:
    # regression: the rehome branch used to open the gripper first, which a finger pressed on the box
    # prevents (OpenGripper TIMEOUT on every later attempt); it now retreats first
    out = run(tmp_path, calibration, RECOVERY, "nudge@Approach#1:dx_m=0.045")
    fault_record(out, "object_nudge")
    first = out.first_failure_after_fault()
    assert (first["leaf"], first["reason"]) == ("Approach", "TRACKING_ERROR")
    assert out.ran("rehome", first["tick"])
    assert out.summary.success, out.summary.to_json()


def test_gripper_slip_during_lift_is_recovered_by_regrasping(tmp_path: Path, calibration: Path) -> None:
    out = run(tmp_path, calibration, RECOVERY, "slip@Lift#1:friction=0.02,force_n=2,duration_s=1.5")
    fault_record(out, "gripper_slip")
    first = out.first_failure_after_fault()
    assert (first["leaf"], first["reason"]) == ("Lift", "SLIPPED")
    assert out.ran("regrasp", first["tick"])
    assert out.summary.success, out.summary.to_json()


def test_depth_hole_over_the_scene_hides_the_object_once(tmp_path: Path, calibration: Path) -> None:
    out = run(tmp_path, calibration, RECOVERY, "hole@Perceive#1:u_px=0,v_px=0,width_px=640,height_px=480")
    fault_record(out, "depth_hole")
    first = out.first_failure_after_fault()
    assert (first["leaf"], first["reason"]) == ("Perceive", "NO_DETECTION")
    assert out.ran("Sleep", first["tick"])
    assert out.summary.success, out.summary.to_json()


def test_depth_burst_fails_perception_cleanly_and_looking_again_recovers(tmp_path: Path, calibration: Path) -> None:
    # 0.5 m of depth noise on every valid pixel of one frame: the red blob no longer stands on the table, so
    # Perceive says NO_DETECTION (a clean failure, not a wrong pose), and the "anything else" branch looks again
    out = run(tmp_path, calibration, RECOVERY, "burst@Perceive#1:sigma_m=0.5")
    record = fault_record(out, "depth_burst")
    assert record["fault"]["details"]["pixels_hit"] > 100_000
    # the damaged frame's detections (none) reach the tree the scene's perception latency later: 0.1 s, 10 ticks
    answered = record["tick"] + 10
    perceive_failures = [f for f in out.failures()
                         if f["leaf"] == "Perceive" and record["tick"] <= f["tick"] <= answered]
    assert [(f["reason"], f["tick"]) for f in perceive_failures] == [("NO_DETECTION", answered)]
    assert out.ran("Sleep", answered)
    assert out.summary.success, out.summary.to_json()


def test_controller_stall_trips_tracking_and_rehomes(tmp_path: Path, calibration: Path) -> None:
    out = run(tmp_path, calibration, RECOVERY, "stall@Approach#1:duration_s=1.5")
    fault_record(out, "controller_stall")
    first = out.first_failure_after_fault()
    assert (first["leaf"], first["reason"]) == ("Approach", "TRACKING_ERROR")
    assert out.ran("rehome", first["tick"])
    assert out.summary.success, out.summary.to_json()


# --- faults pick.xml has no answer to: the run fails, and says where and why ------------------------------------


def test_calibration_offset_makes_the_pick_miss(tmp_path: Path, calibration: Path) -> None:
    # armed on entering Perceive (a tick trigger would come too late: tick 1 already runs Perceive .. Approach)
    # a camera 60 mm off along y puts the grasp 60 mm off along the fingers' closing axis: a finger comes down
    # on the box (as a 60-70 mm nudge along y does) and the descent cannot settle
    out = run(tmp_path, calibration, PICK, "calib@Perceive#1:dy_mm=60")
    record = fault_record(out, "calibration_offset")
    assert record["fault"]["leaf"] == "Perceive"
    first = out.first_failure_after_fault()
    assert (first["leaf"], first["reason"]) == ("Approach", "TRACKING_ERROR")
    assert first["message"].startswith("descend:"), first["message"]
    assert not out.summary.success
    assert (out.summary.failed_leaf, out.summary.reason) == ("Approach", "TRACKING_ERROR")


def test_leaf_timeout_hangs_approach_until_its_watchdog_fires(tmp_path: Path, calibration: Path) -> None:
    # the cell ignores the arm's commands: Approach's watchdog is the executor's tracking check (TIMEOUT is
    # the gripper leaves' watchdog), and it fires while the cell is still not responding
    out = run(tmp_path, calibration, PICK, "timeout@Approach#1:duration_s=3")
    record = fault_record(out, "leaf_timeout")
    assert record["fault"]["leaf"] == "Approach"
    first = out.first_failure_after_fault()
    assert (first["leaf"], first["reason"]) == ("Approach", "TRACKING_ERROR")
    assert first["stamp_ns"] < record["fault"]["details"]["until_ns"]
    assert not out.summary.success
    assert (out.summary.failed_leaf, out.summary.reason) == ("Approach", "TRACKING_ERROR")
