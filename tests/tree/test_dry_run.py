"""`bt-grasp tree run --dry`: every robot leaf a stand-in with no flag, outcomes steering the walk into the
recovery branches, a reproducible random mode, one sentence for a bad outcome; wildcards leave Script alone.

The expected walks are written out as BT.CPP's StdCoutLogger shows them: every status change of every node in order
(``path FROM -> TO``), with the tick it happened in; a completed control resets its children to IDLE, a halt
brings a RUNNING node back to IDLE."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from bt_grasp.behaviours.library import robot_registry
from bt_grasp.behaviours.reasons import FailureReason
from bt_grasp.cli.main import main

from .harness import Harness

TREES = Path(__file__).resolve().parents[2] / "trees"
STACK = str(TREES / "stack.xml")
RECOVERY = str(TREES / "pick_with_recovery.xml")


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def walk_lines(out: str) -> list[str]:
    lines = out.splitlines()
    return lines[next(i for i, line in enumerate(lines) if line.startswith("tick 1:")) :]


def moves(result: dict[str, Any], *, resets: bool = True) -> list[str]:
    """The walk as ``path FROM -> TO`` (``resets=False``: without the changes back to IDLE)."""
    return [f"{t['path']} {t['from']} -> {t['to']}" for t in result["transitions"] if resets or t["to"] != "IDLE"]


def test_stack_runs_dry_with_no_other_flag(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(capsys, "tree", "run", "--dry", STACK)
    assert (code, err) == (0, "") and out.startswith("SUCCESS after 1 ticks\n")
    # every stand-in succeeds: PerceiveAll writes three boxes, the real SelectObject picks the blue one,
    # IsGrasped (SUCCESS) skips the pick, PlaceOn succeeds, MoveHome too: one tick. Each line is a status
    # change (StdCoutLogger's columns); a completed Sequence resets its children to IDLE, then itself ends
    lines = walk_lines(out)
    assert lines[:9] == [
        "tick 1: SUCCESS",
        "[0.000]: stack                     IDLE -> RUNNING",
        "[0.000]: LoadCalibration::2        IDLE -> SUCCESS",
        "[0.000]: Script::3                 IDLE -> SUCCESS",
        "[0.000]: RetryUntilSuccessful::4   IDLE -> RUNNING",
        "[0.000]: pick_then_stack           IDLE -> RUNNING",
        "[0.000]: PerceiveAll::6            IDLE -> SUCCESS",
        "[0.000]: SelectObject::7           IDLE -> SUCCESS",
        "[0.000]: PickObject::8             IDLE -> RUNNING",
    ]
    assert [line[9:] for line in lines[9:] if not line.endswith("-> IDLE")] == [
        "PickObject::8/holding_or_pick IDLE -> RUNNING",
        "PickObject::8/IsGrasped::10 IDLE -> SUCCESS",
        "PickObject::8/holding_or_pick RUNNING -> SUCCESS",
        "PickObject::8             RUNNING -> SUCCESS",
        "PlaceOnObject::56         IDLE -> RUNNING",
        "PlaceOnObject::56/RetryUntilSuccessful::57 IDLE -> RUNNING",
        "PlaceOnObject::56/place_on_or_recover IDLE -> RUNNING",
        "PlaceOnObject::56/place_on IDLE -> RUNNING",
        "PlaceOnObject::56/IsGrasped::60 IDLE -> SUCCESS",
        "PlaceOnObject::56/PlaceOn::61 IDLE -> SUCCESS",
        "PlaceOnObject::56/place_on RUNNING -> SUCCESS",
        "PlaceOnObject::56/place_on_or_recover RUNNING -> SUCCESS",
        "PlaceOnObject::56/RetryUntilSuccessful::57 RUNNING -> SUCCESS",
        "PlaceOnObject::56         RUNNING -> SUCCESS",
        "pick_then_stack           RUNNING -> SUCCESS",
        "RetryUntilSuccessful::4   RUNNING -> SUCCESS",
        "MoveHome::97              IDLE -> SUCCESS",
        "stack                     RUNNING -> SUCCESS",
    ]
    assert lines[-1] == "[0.000]: stack                     SUCCESS -> IDLE"  # BT.CPP's tickOnce resets the root
    assert "  support = Detection(label='blue'" in out  # the stand-in's detections reached SelectObject


#: one attempt of pick_with_recovery.xml when PlanGrasp fails with IK_UNREACHABLE, from its Attempt SubTree's
#: failure: the recovery branch chosen by the reason (next_candidate_ik: FailureIs matches, skip += 1) runs, every
#: child it completed is reset to IDLE by its parent, and ForceFailure fails the attempt again
ATTEMPT_IK = [
    "Attempt::6/OpenGripper::8 IDLE -> SUCCESS",
    "Attempt::6/see_or_search IDLE -> RUNNING",
    "Attempt::6/Perceive::10 IDLE -> SUCCESS",
    "Attempt::6/Perceive::10 SUCCESS -> IDLE",  # the Fallback resets the child that succeeded (search_lost not run)
    "Attempt::6/see_or_search RUNNING -> SUCCESS",
    "Attempt::6/PlanGrasp::16 IDLE -> FAILURE",
    "Attempt::6/OpenGripper::8 SUCCESS -> IDLE",
    "Attempt::6/see_or_search SUCCESS -> IDLE",
    "Attempt::6/PlanGrasp::16 FAILURE -> IDLE",
    "Attempt::6/attempt RUNNING -> FAILURE",
    "Attempt::6/attempt FAILURE -> IDLE",
    "Attempt::6 RUNNING -> FAILURE",
    "ForceFailure::20 IDLE -> RUNNING",
    "Recover::21 IDLE -> RUNNING",
    "Recover::21/recover IDLE -> RUNNING",
    "Recover::21/by_reason IDLE -> RUNNING",
    "Recover::21/next_candidate IDLE -> RUNNING",
    "Recover::21/FailureIs::25 IDLE -> FAILURE",  # PLAN_FAILED? no
    "Recover::21/FailureIs::25 FAILURE -> IDLE",
    "Recover::21/next_candidate RUNNING -> FAILURE",
    "Recover::21/next_candidate_ik IDLE -> RUNNING",
    "Recover::21/FailureIs::28 IDLE -> SUCCESS",  # IK_UNREACHABLE? yes
    "Recover::21/Script::29 IDLE -> SUCCESS",  # skip += 1
    "Recover::21/FailureIs::28 SUCCESS -> IDLE",
    "Recover::21/Script::29 SUCCESS -> IDLE",
    "Recover::21/next_candidate_ik RUNNING -> SUCCESS",
    "Recover::21/next_candidate FAILURE -> IDLE",  # the Fallback resets the child that failed before
    "Recover::21/next_candidate_ik SUCCESS -> IDLE",
    "Recover::21/by_reason RUNNING -> SUCCESS",
    "Recover::21/by_reason SUCCESS -> IDLE",
    "Recover::21/recover RUNNING -> SUCCESS",
    "Recover::21/recover SUCCESS -> IDLE",
    "Recover::21 RUNNING -> SUCCESS",
    "Recover::21 SUCCESS -> IDLE",
    "ForceFailure::20 RUNNING -> FAILURE",
    "Attempt::6 FAILURE -> IDLE",
    "ForceFailure::20 FAILURE -> IDLE",
    "attempt_or_recover RUNNING -> FAILURE",
    "attempt_or_recover FAILURE -> IDLE",  # RetryUntilSuccessful resets it and asks for a wake-up
]
#: the start of each retried attempt (the root ran again within the tick)
RETRY = ["attempt_or_recover IDLE -> RUNNING", "Attempt::6 IDLE -> RUNNING", "Attempt::6/attempt IDLE -> RUNNING"]


def test_an_outcome_steers_pick_with_recovery_into_its_ik_branch(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(
        capsys, "tree", "run", "--dry", RECOVERY, "--outcome", "PlanGrasp=failure:IK_UNREACHABLE", "--json"
    )
    result = json.loads(out)
    assert (code, err, result["status"], result["ticks"]) == (1, "", "FAILURE", 1)
    # tick 1, five root executions: RetryUntilSuccessful wakes the root after each failed attempt; the fifth
    # failure makes it give up
    assert result["walk"] == [{"tick": 1, "status": "FAILURE", "runs": 5}]
    start = ["pick IDLE -> RUNNING", "Script::2 IDLE -> SUCCESS", "LoadCalibration::3 IDLE -> SUCCESS",
             "RetryUntilSuccessful::4 IDLE -> RUNNING"]
    last = ["RetryUntilSuccessful::4 RUNNING -> FAILURE", "Script::2 SUCCESS -> IDLE",
            "LoadCalibration::3 SUCCESS -> IDLE", "RetryUntilSuccessful::4 FAILURE -> IDLE", "pick RUNNING -> FAILURE",
            "pick FAILURE -> IDLE"]
    assert moves(result) == [*start, *(RETRY + ATTEMPT_IK) * 5, *last]
    # the stand-in wrote what a real PlanGrasp writes on failure
    bb = result["blackboard"]
    assert (bb["failure_reason"], bb["failed_leaf"], bb["skip"]) == ("IK_UNREACHABLE", "PlanGrasp", 5)


def test_a_grasp_that_closes_on_nothing_walks_the_regrasp_branch(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "tree", "run", "--dry", RECOVERY, "--outcome", "Grasp=failure:GRASP_EMPTY", "--json")
    result = json.loads(out)
    assert code == 1 and result["walk"] == [{"tick": 1, "status": "FAILURE", "runs": 5}]
    # after the attempt (OpenGripper, Perceive, PlanGrasp, Approach SUCCESS; Grasp FAILURE): the two
    # next_candidate branches fail on their FailureIs, regrasp matches GRASP_EMPTY and its robot leaves run
    walk = moves(result, resets=False)
    first = walk[walk.index("ForceFailure::20 IDLE -> RUNNING"): walk.index("ForceFailure::20 RUNNING -> FAILURE")]
    assert first == [
        "ForceFailure::20 IDLE -> RUNNING",
        "Recover::21 IDLE -> RUNNING",
        "Recover::21/recover IDLE -> RUNNING",
        "Recover::21/by_reason IDLE -> RUNNING",
        "Recover::21/next_candidate IDLE -> RUNNING",
        "Recover::21/FailureIs::25 IDLE -> FAILURE",
        "Recover::21/next_candidate RUNNING -> FAILURE",
        "Recover::21/next_candidate_ik IDLE -> RUNNING",
        "Recover::21/FailureIs::28 IDLE -> FAILURE",
        "Recover::21/next_candidate_ik RUNNING -> FAILURE",
        "Recover::21/regrasp IDLE -> RUNNING",
        "Recover::21/Fallback::31 IDLE -> RUNNING",
        "Recover::21/FailureIs::32 IDLE -> SUCCESS",  # GRASP_EMPTY
        "Recover::21/Fallback::31 RUNNING -> SUCCESS",
        "Recover::21/OpenGripper::34 IDLE -> SUCCESS",
        "Recover::21/Retreat::35 IDLE -> SUCCESS",
        "Recover::21/MoveHome::36 IDLE -> SUCCESS",
        "Recover::21/Script::37 IDLE -> SUCCESS",  # skip := 0
        "Recover::21/regrasp RUNNING -> SUCCESS",
        "Recover::21/by_reason RUNNING -> SUCCESS",
        "Recover::21/recover RUNNING -> SUCCESS",
        "Recover::21 RUNNING -> SUCCESS",
    ]


def test_a_running_outcome_spreads_over_ticks(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "tree", "run", "--dry", RECOVERY, "--outcome", "Lift=running:2")
    lines = walk_lines(out)
    # tick 1: the attempt runs up to Lift, which stays RUNNING; tick 2 changes nothing (every node on the way
    # stays RUNNING: no line); at tick 3 (20 ms later) Lift succeeds and the Sequences complete upwards
    assert code == 0 and lines[0] == "tick 1: RUNNING"
    assert lines[16] == "[0.000]: Attempt::6/Lift::19       IDLE -> RUNNING"
    assert [line for line in lines[17:] if not line.endswith("-> IDLE")] == [
        "tick 2: RUNNING",
        "tick 3: SUCCESS",
        "[0.020]: Attempt::6/Lift::19       RUNNING -> SUCCESS",
        "[0.020]: Attempt::6/attempt        RUNNING -> SUCCESS",
        "[0.020]: Attempt::6                RUNNING -> SUCCESS",
        "[0.020]: attempt_or_recover        RUNNING -> SUCCESS",
        "[0.020]: RetryUntilSuccessful::4   RUNNING -> SUCCESS",
        "[0.020]: pick                      RUNNING -> SUCCESS",
    ]


def test_a_named_non_robot_leaf_becomes_a_stand_in_only_when_asked(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(
        capsys, "tree", "run", "--dry", STACK, "--outcome", "SelectObject=failure:NO_DETECTION", "--json"
    )
    result = json.loads(out)
    # SelectObject fails in each of the 3 attempts -> the retry gives up -> FAILURE, reason written
    assert code == 1 and result["walk"][0]["runs"] == 3
    assert moves(result).count("SelectObject::7 IDLE -> FAILURE") == 3
    assert (result["blackboard"]["failure_reason"], result["blackboard"]["failed_leaf"]) == (
        "NO_DETECTION",
        "SelectObject",
    )


def test_random_mode_is_reproducible_and_explores_failures(capsys: pytest.CaptureFixture[str]) -> None:
    outs = [run_cli(capsys, "tree", "run", "--dry", RECOVERY, "--random", "3", "--json")[1] for _ in range(2)]
    assert outs[0] == outs[1]
    result = json.loads(outs[0])
    failed = {(move["type"], move["to"]) for move in result["transitions"] if move["to"] == "FAILURE"}
    assert len(failed) >= 2  # not the all-success walk: some robot leaves failed and recovery branches ran
    other = run_cli(capsys, "tree", "run", "--dry", RECOVERY, "--random", "4", "--json")[1]
    assert json.loads(other)["transitions"] != result["transitions"]


@pytest.mark.parametrize(
    ("outcome", "sentence"),
    [
        (
            "Teleport=success",
            "--outcome 'Teleport=success': the name 'Teleport' matches no leaf of this tree (by type, name or full "
            "path; stand-ins: Approach, FindLost, Grasp, Lift, LoadCalibration, MoveHome, OpenGripper, Perceive, "
            "PerceiveAll, PlanGrasp, Retreat)",
        ),
        (
            "PlanGrasp=failure:SLIPPED",
            "--outcome 'PlanGrasp=failure:SLIPPED': PlanGrasp does not fail with SLIPPED; it declares "
            "NO_DETECTION, NOTHING_TO_GRASP, IK_UNREACHABLE, PLAN_FAILED",
        ),
        ("PlanGrasp=failure:NOPE", "--outcome 'PlanGrasp=failure:NOPE': NOPE is not a failure reason bt_grasp knows"),
        (
            "PlanGrasp=explode",
            "--outcome 'PlanGrasp=explode': 'explode' is not an outcome: the syntax is NAME=OUTCOME[,OUTCOME...], "
            "each success, failure[:REASON] or running:N[:failure[:REASON]]",
        ),
        ("PlanGrasp", "--outcome 'PlanGrasp': is not NAME=OUTCOME[,OUTCOME...], each success, failure[:REASON] or "
                      "running:N[:failure[:REASON]]"),
        ("Plan*=failure", "--outcome 'Plan*=failure': the pattern 'Plan*' matches no leaf of this tree (by type, name "
                          "or full path; stand-ins: Approach, FindLost, Grasp, Lift, LoadCalibration, MoveHome, "
                          "OpenGripper, Perceive, PerceiveAll, PlanGrasp, Retreat)"),
    ],
)
def test_a_bad_outcome_is_one_sentence_and_exit_2(
    outcome: str, sentence: str, capsys: pytest.CaptureFixture[str]
) -> None:
    code, out, err = run_cli(capsys, "tree", "run", "--dry", RECOVERY, "--outcome", outcome)
    assert (code, out, err) == (2, "", "bt-grasp: error: " + sentence + "\n")


def test_a_wildcard_substitutes_robot_leaves_only_unless_a_kind_is_named() -> None:
    xml = '<Sequence><Script code="x := 1"/><Arm name="Move"/><Stub name="S"/></Sequence>'
    wild = Harness(xml, substitutions={"*": "AlwaysFailure"})
    # the Script ran as written and the Stub was built (never ticked: the Sequence stopped at the robot leaf
    # Arm, the only node the wildcard replaced: Stub is bt_grasp's own here, not a plugin's or a model's)
    assert wild.tick() == "FAILURE" and wild.bb["x"] == 1 and wild["S"].ticks == 0
    assert [wild.node(name).bt_type for name in ("Script::2", "Move", "S")] == ["Script", "AlwaysFailure", "Stub"]
    named = Harness(xml, substitutions={"Script": "AlwaysFailure"})
    assert named.tick() == "FAILURE" and "x" not in named.bb


def test_every_robot_leaf_declares_its_failure_reasons() -> None:
    specs = [spec for spec in robot_registry(installed=False).specs() if spec.needs_robot]
    known = {r.value for r in FailureReason}
    assert all(spec.failure_reasons and set(spec.failure_reasons) <= known for spec in specs)
