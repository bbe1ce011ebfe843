"""`bt-grasp tree run --dry`: every robot leaf a stand-in with no flag, outcomes steering the walk into the
recovery branches, a reproducible random mode, one sentence for a bad outcome; wildcards leave Script alone.

The expected walks are written out tick by tick: each line is a node that returned during the tick (or the
root execution), indented by depth, with the status it returned."""

from __future__ import annotations

import json
from pathlib import Path

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


def statuses(run: list[dict[str, str]]) -> list[tuple[str, str]]:
    return [(step["path"].rsplit("/", 1)[-1], step["status"]) for step in run]


def test_stack_runs_dry_with_no_other_flag(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(capsys, "tree", "run", "--dry", STACK)
    assert (code, err) == (0, "") and out.startswith("SUCCESS after 1 ticks\n")
    # every stand-in succeeds: PerceiveAll writes three boxes, the real SelectObject picks the blue one,
    # IsGrasped (SUCCESS) skips the pick, PlaceOn succeeds, MoveHome too: one tick
    assert walk_lines(out) == [
        "tick 1: SUCCESS",
        "  stack [Sequence] SUCCESS",
        "    LoadCalibration::2 [LoadCalibration] SUCCESS",
        "    Script::3 [Script] SUCCESS",
        "    RetryUntilSuccessful::4 [RetryUntilSuccessful] SUCCESS",
        "      pick_then_stack [Sequence] SUCCESS",
        "        PerceiveAll::6 [PerceiveAll] SUCCESS",
        "        SelectObject::7 [SelectObject] SUCCESS",
        "        PickObject::8 [SubTree] SUCCESS",
        "          holding_or_pick [Fallback] SUCCESS",
        "            IsGrasped::10 [IsGrasped] SUCCESS",
        "        PlaceOnObject::50 [SubTree] SUCCESS",
        "          RetryUntilSuccessful::51 [RetryUntilSuccessful] SUCCESS",
        "            place_on_or_recover [Fallback] SUCCESS",
        "              place_on [Sequence] SUCCESS",
        "                IsGrasped::54 [IsGrasped] SUCCESS",
        "                PlaceOn::55 [PlaceOn] SUCCESS",
        "    MoveHome::73 [MoveHome] SUCCESS",
    ]
    assert "  support = Detection(label='blue'" in out  # the stand-in's detections reached SelectObject


#: one attempt of pick_with_recovery.xml when PlanGrasp fails with IK_UNREACHABLE: the recovery branch
#: chosen by the reason (next_candidate_ik) adds 1 to skip; ForceFailure makes the attempt fail again
ATTEMPT_IK = [
    ("attempt_or_recover", "FAILURE"),
    ("Attempt::6", "FAILURE"),
    ("attempt", "FAILURE"),
    ("OpenGripper::8", "SUCCESS"),
    ("Perceive::9", "SUCCESS"),
    ("PlanGrasp::10", "FAILURE"),
    ("ForceFailure::14", "FAILURE"),
    ("Recover::15", "SUCCESS"),
    ("recover", "SUCCESS"),
    ("by_reason", "SUCCESS"),
    ("next_candidate", "FAILURE"),
    ("FailureIs::19", "FAILURE"),  # PLAN_FAILED? no
    ("next_candidate_ik", "SUCCESS"),
    ("FailureIs::22", "SUCCESS"),  # IK_UNREACHABLE? yes
    ("Script::23", "SUCCESS"),  # skip += 1
]


def test_an_outcome_steers_pick_with_recovery_into_its_ik_branch(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(
        capsys, "tree", "run", "--dry", RECOVERY, "--outcome", "PlanGrasp=failure:IK_UNREACHABLE", "--json"
    )
    result = json.loads(out)
    assert (code, err, result["status"], result["ticks"]) == (1, "", "FAILURE", 1)
    (tick,) = result["walk"]
    # tick 1, five root executions (RetryUntilSuccessful wakes the root after each failed attempt):
    # run 1 starts the tree; runs 2-4 retry; run 5 is the fifth failed attempt: the retry gives up
    assert tick["status"] == "FAILURE" and len(tick["runs"]) == 5
    first, *middle, last = tick["runs"]
    start = [("pick", "RUNNING"), ("Script::2", "SUCCESS"), ("LoadCalibration::3", "SUCCESS")]
    assert statuses(first) == [*start, ("RetryUntilSuccessful::4", "RUNNING"), *ATTEMPT_IK]
    for run in middle:
        assert statuses(run) == [("pick", "RUNNING"), ("RetryUntilSuccessful::4", "RUNNING"), *ATTEMPT_IK]
    assert statuses(last) == [("pick", "FAILURE"), ("RetryUntilSuccessful::4", "FAILURE"), *ATTEMPT_IK]
    # the stand-in wrote what a real PlanGrasp writes on failure
    bb = result["blackboard"]
    assert (bb["failure_reason"], bb["failed_leaf"], bb["skip"]) == ("IK_UNREACHABLE", "PlanGrasp", 5)


def test_a_grasp_that_closes_on_nothing_walks_the_regrasp_branch(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "tree", "run", "--dry", RECOVERY, "--outcome", "Grasp=failure:GRASP_EMPTY", "--json")
    (tick,) = json.loads(out)["walk"]
    assert code == 1 and len(tick["runs"]) == 5
    # run 1 after the attempt (OpenGripper, Perceive, PlanGrasp, Approach SUCCESS; Grasp FAILURE): the two
    # next_candidate branches fail on their FailureIs, regrasp matches GRASP_EMPTY and its robot leaves run
    recovery = statuses(tick["runs"][0])[statuses(tick["runs"][0]).index(("ForceFailure::14", "FAILURE")) :]
    assert recovery == [
        ("ForceFailure::14", "FAILURE"),
        ("Recover::15", "SUCCESS"),
        ("recover", "SUCCESS"),
        ("by_reason", "SUCCESS"),
        ("next_candidate", "FAILURE"),
        ("FailureIs::19", "FAILURE"),
        ("next_candidate_ik", "FAILURE"),
        ("FailureIs::22", "FAILURE"),
        ("regrasp", "SUCCESS"),
        ("Fallback::25", "SUCCESS"),
        ("FailureIs::26", "SUCCESS"),  # GRASP_EMPTY
        ("OpenGripper::28", "SUCCESS"),
        ("Retreat::29", "SUCCESS"),
        ("MoveHome::30", "SUCCESS"),
        ("Script::31", "SUCCESS"),  # skip := 0
    ]


def test_a_running_outcome_spreads_over_ticks(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "tree", "run", "--dry", RECOVERY, "--outcome", "Lift=running:2")
    lines = walk_lines(out)
    # tick 1: the attempt runs up to Lift, which stays RUNNING; ticks 2 and 3 resume at Lift (the Sequence
    # has memory of its running child): RUNNING, then SUCCESS
    assert code == 0 and lines[0] == "tick 1: RUNNING" and lines[13] == "            Lift::13 [Lift] RUNNING"
    resumed = [
        "  pick [Sequence] {0}",
        "    RetryUntilSuccessful::4 [RetryUntilSuccessful] {0}",
        "      attempt_or_recover [Fallback] {0}",
        "        Attempt::6 [SubTree] {0}",
        "          attempt [Sequence] {0}",
        "            Lift::13 [Lift] {0}",
    ]
    assert lines[14:] == [
        "tick 2: RUNNING", *(line.format("RUNNING") for line in resumed),
        "tick 3: SUCCESS", *(line.format("SUCCESS") for line in resumed),
    ]  # fmt: skip


def test_a_named_non_robot_leaf_becomes_a_stand_in_only_when_asked(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(
        capsys, "tree", "run", "--dry", STACK, "--outcome", "SelectObject=failure:NO_DETECTION", "--json"
    )
    result = json.loads(out)
    # SelectObject fails in each of the 3 attempts -> the retry gives up -> FAILURE, reason written
    assert code == 1 and len(result["walk"][0]["runs"]) == 3
    assert (result["blackboard"]["failure_reason"], result["blackboard"]["failed_leaf"]) == (
        "NO_DETECTION",
        "SelectObject",
    )


def test_random_mode_is_reproducible_and_explores_failures(capsys: pytest.CaptureFixture[str]) -> None:
    outs = [run_cli(capsys, "tree", "run", "--dry", RECOVERY, "--random", "3", "--json")[1] for _ in range(2)]
    assert outs[0] == outs[1]
    result = json.loads(outs[0])
    failed = {
        (step["type"], step["status"])
        for tick in result["walk"]
        for run in tick["runs"]
        for step in run
        if step["status"] == "FAILURE"
    }
    assert len(failed) >= 2  # not the all-success walk: some robot leaves failed and recovery branches ran
    other = run_cli(capsys, "tree", "run", "--dry", RECOVERY, "--random", "4", "--json")[1]
    assert json.loads(other)["walk"] != result["walk"]


@pytest.mark.parametrize(
    ("outcome", "sentence"),
    [
        (
            "Teleport=success",
            "--outcome 'Teleport=success': 'Teleport' is no leaf type, name or path of this tree (robot leaves: "
            "Approach, Grasp, Lift, LoadCalibration, MoveHome, OpenGripper, Perceive, PlanGrasp, Retreat)",
        ),
        (
            "PlanGrasp=failure:SLIPPED",
            "--outcome 'PlanGrasp=failure:SLIPPED': PlanGrasp does not fail with SLIPPED; it declares "
            "NO_DETECTION, NOTHING_TO_GRASP, IK_UNREACHABLE, PLAN_FAILED",
        ),
        ("PlanGrasp=failure:NOPE", "--outcome 'PlanGrasp=failure:NOPE': NOPE is not a failure reason bt_grasp knows"),
        (
            "PlanGrasp=explode",
            "--outcome 'PlanGrasp=explode': the outcome must be NAME=success, NAME=failure[:REASON] or NAME=running:N",
        ),
        ("PlanGrasp", "--outcome 'PlanGrasp': is not NAME=success, NAME=failure[:REASON] or NAME=running:N"),
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
    # Arm, the only node the wildcard replaced)
    assert wild.tick() == "FAILURE" and wild.bb["x"] == 1 and wild["S"].ticks == 0
    assert [wild.node(name).bt_type for name in ("Script::2", "Move", "S")] == ["Script", "AlwaysFailure", "Stub"]
    named = Harness(xml, substitutions={"Script": "AlwaysFailure"})
    assert named.tick() == "FAILURE" and "x" not in named.bb


def test_every_robot_leaf_declares_its_failure_reasons() -> None:
    specs = [spec for spec in robot_registry(installed=False).specs() if spec.needs_robot]
    known = {r.value for r in FailureReason}
    assert all(spec.failure_reasons and set(spec.failure_reasons) <= known for spec in specs)
