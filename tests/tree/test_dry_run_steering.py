"""Issue 44: a dry run steered as BehaviorTree.CPP tests are. One test per finding of the issue's "Why" (each
failed on main before the issue), and issue 43's finding 10 (a tree checked against its scene).

Walks are written as ``tree run`` prints them, BT.CPP's StdCoutLogger columns with the full path for the name:
``[time]: path  FROM -> TO``, every status change in order, tick by tick."""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import pytest

from bt_grasp.cli.main import main

REPO = Path(__file__).resolve().parents[2]
NAV2 = REPO / "tests" / "data" / "nav2"
RULES = REPO / "tests" / "tree_conformance" / "rules"

#: a mission whose leaves exist only in its own TreeNodesModel (as Groot2 saves one)
MODEL_TREE = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence name="mission">
      <ReadBattery level="{level}" report="{report}"/>
      <IsCharged level="{level}"/>
      <ScriptCondition code="level == 0 &amp;&amp; report == ''"/>
    </Sequence>
  </BehaviorTree>
  <TreeNodesModel>
    <Action ID="ReadBattery">
      <output_port name="level" type="int">charge in percent</output_port>
      <output_port name="report" type="std::string"/>
    </Action>
    <Condition ID="IsCharged">
      <input_port name="level" type="unsigned int" default="{level}"/>
    </Condition>
  </TreeNodesModel>
</root>
"""

#: the walk of MODEL_TREE when every stand-in succeeds: one tick
MODEL_WALK = [
    "tick 1: SUCCESS",
    "[0.000]: mission                   IDLE -> RUNNING",
    "[0.000]: ReadBattery::2            IDLE -> SUCCESS",  # writes level = 0, report = "" (its types' defaults)
    "[0.000]: IsCharged::3              IDLE -> SUCCESS",
    "[0.000]: ScriptCondition::4        IDLE -> SUCCESS",  # level == 0 && report == '': the outputs were written
    "[0.000]: ReadBattery::2            SUCCESS -> IDLE",  # the Sequence completed: it resets its children
    "[0.000]: IsCharged::3              SUCCESS -> IDLE",
    "[0.000]: ScriptCondition::4        SUCCESS -> IDLE",
    "[0.000]: mission                   RUNNING -> SUCCESS",
    "[0.000]: mission                   SUCCESS -> IDLE",  # BT.CPP's tickOnce resets a completed root
]


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def walk(out: str) -> list[str]:
    lines = out.splitlines()
    return lines[next(i for i, line in enumerate(lines) if line.startswith("tick 1:")):]


def moves(result: dict[str, Any]) -> list[str]:
    return [f"{t['tick']} {t['path']} {t['from']} -> {t['to']}" for t in result["transitions"]]


def write(folder: Path, name: str, text: str) -> str:
    (folder / name).write_text(text)
    return str(folder / name)


# ---- 1. every node needed a Python class, although the project's TreeNodesModel declares every port ----------
def test_leaves_only_a_model_declares_run_with_no_python(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tree = write(tmp_path, "battery.xml", MODEL_TREE)
    code, out, err = run_cli(capsys, "tree", "run", "--dry", tree)
    assert (code, err) == (0, "") and walk(out) == MODEL_WALK
    assert out.startswith("SUCCESS after 1 ticks\n  level = 0\n")
    # the model is the node's manifest: an attribute it does not declare is refused at its line
    bad = write(tmp_path, "bad.xml", MODEL_TREE.replace('<IsCharged level="{level}"/>', '<IsCharged levl="3"/>'))
    code, _, err = run_cli(capsys, "tree", "run", "--dry", bad)
    assert code == 2 and err.startswith(f"bt-grasp: error: {bad}:5: unknown attribute 'levl' for IsCharged"), err
    # the model in a file of its own (--nodes-model), as Nav2's nav2_tree_nodes.xml
    bare = write(tmp_path, "bare.xml", re.sub(r"\s*<TreeNodesModel>.*</TreeNodesModel>", "", MODEL_TREE, flags=re.S))
    models = write(tmp_path, "nodes.xml", '<root BTCPP_format="4">' + MODEL_TREE[MODEL_TREE.index("<TreeNodesModel>"):])
    code, out, err = run_cli(capsys, "tree", "run", "--dry", bare, "--nodes-model", models)
    assert (code, err) == (0, "") and walk(out) == MODEL_WALK
    # tree stubs: a plugin of typed stand-ins in the node API, which loads with --leaves and ticks the same
    stubs = tmp_path / "battery_nodes.py"
    code, out, _ = run_cli(capsys, "tree", "stubs", models, "--out", str(stubs))
    assert (code, out) == (0, f"wrote 2 stand-ins to {stubs} (load it with --leaves {stubs})\n")
    text = stubs.read_text()
    assert "@bt.action(ports=[\n    bt.output_port('level', int, 'charge in percent')," in text
    assert "class IsCharged(bt.Leaf):" in text and "registry.register(node, node_id)" in text
    code, out, err = run_cli(capsys, "tree", "run", "--dry", "--leaves", str(stubs), bare)
    assert (code, err) == (0, "") and walk(out) == MODEL_WALK
    code, out, _ = run_cli(capsys, "tree", "validate", "--leaves", str(stubs), bare)
    assert code == 0 and out.endswith("OK (4 nodes, main tree Main)\n")


# ---- 2. --outcome was one outcome per node for the whole run -------------------------------------------------
def test_an_outcome_per_call_the_last_repeating(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tree = write(tmp_path, "retry.xml", """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <RetryUntilSuccessful num_attempts="5">
      <Sequence name="go"><Plan/><Drive/></Sequence>
    </RetryUntilSuccessful>
  </BehaviorTree>
  <TreeNodesModel><Action ID="Plan"/><Action ID="Drive"/></TreeNodesModel>
</root>
""")
    code, out, err = run_cli(capsys, "tree", "run", "--dry", tree,
                             "--outcome", "Plan=failure,running:1:failure,success")
    assert (code, err) == (0, "")
    assert walk(out) == [
        # call 1 fails at once: the retry resets the Sequence and wakes the root, which runs again in the tick;
        # call 2 starts and stays RUNNING for one tick
        "tick 1: RUNNING (2 root runs)",
        "[0.000]: RetryUntilSuccessful::1   IDLE -> RUNNING",
        "[0.000]: go                        IDLE -> RUNNING",
        "[0.000]: Plan::3                   IDLE -> FAILURE",
        "[0.000]: Plan::3                   FAILURE -> IDLE",
        "[0.000]: go                        RUNNING -> FAILURE",
        "[0.000]: go                        FAILURE -> IDLE",
        "[0.000]: go                        IDLE -> RUNNING",
        "[0.000]: Plan::3                   IDLE -> RUNNING",
        # call 2 then fails; a child that had been RUNNING is retried in the same execution: call 3 succeeds
        "tick 2: SUCCESS",
        "[0.010]: Plan::3                   RUNNING -> FAILURE",
        "[0.010]: Plan::3                   FAILURE -> IDLE",
        "[0.010]: go                        RUNNING -> FAILURE",
        "[0.010]: go                        FAILURE -> IDLE",
        "[0.010]: go                        IDLE -> RUNNING",
        "[0.010]: Plan::3                   IDLE -> SUCCESS",
        "[0.010]: Drive::4                  IDLE -> SUCCESS",
        "[0.010]: Plan::3                   SUCCESS -> IDLE",
        "[0.010]: Drive::4                  SUCCESS -> IDLE",
        "[0.010]: go                        RUNNING -> SUCCESS",
        "[0.010]: go                        SUCCESS -> IDLE",
        "[0.010]: RetryUntilSuccessful::1   RUNNING -> SUCCESS",
        "[0.010]: RetryUntilSuccessful::1   SUCCESS -> IDLE",
    ]
    # the last outcome repeats: with failure alone the retry gives up after its 5 attempts in one tick
    code, out, _ = run_cli(capsys, "tree", "run", "--dry", tree, "--outcome", "Plan=success,failure", "--json")
    assert code == 0 and moves(json.loads(out)).count("1 Plan::3 IDLE -> FAILURE") == 0
    code, out, _ = run_cli(capsys, "tree", "run", "--dry", tree, "--outcome", "Plan=failure", "--json")
    result = json.loads(out)
    assert code == 1 and moves(result).count("1 Plan::3 IDLE -> FAILURE") == 5 and result["walk"][0]["runs"] == 5


# ---- 3. BT.CPP's substitution rules (loadSubstitutionRuleFromJSON) were not read -------------------------------
def test_btcpp_substitution_rules_steer_a_tree_of_model_leaves(capsys: pytest.CaptureFixture[str]) -> None:
    tree, rules = RULES / "rules_mission_exact.xml", RULES / "rules_mission_exact.rules.json"
    code, out, err = run_cli(capsys, "tree", "run", "--dry", str(tree), "--substitution-rules", str(rules), "--json",
                             "--no-plugins", "--set", "tries=0", "--set", "polls=0")
    assert (code, err) == (0, "")  # replacing a control or a SubTree by name on purpose is no cause for a warning
    result = json.loads(out)
    assert result["blackboard"] == {"tries": 3, "polls": 3, "level": 0, "plan_error": "", "planned": 3}
    walk_1 = [m for m in moves(result) if m.startswith("1 ") and not m.endswith("-> IDLE")]
    # tick 1: Plan (rule by type: the script counts tries) fails twice, RetryUntilSuccessful retries; the third
    # try plans, Drive (rule by name) fails, the SubTree named "spare" is replaced as a whole (it fails), the
    # "recover" SubTree runs: Wait2 is the model's stand-in, ClearMap the rule "recover/Clear*" over its path;
    # the Sequence "report_block" is replaced (its two Beeps left out of the tree, their uids 14 and 15 BT.CPP's)
    assert walk_1[:3] == ["1 mission IDLE -> RUNNING", "1 CheckBattery::2 IDLE -> SUCCESS",
                          "1 RetryUntilSuccessful::3 IDLE -> RUNNING"]
    assert [m for m in walk_1 if "Plan" in m] == ["1 Plan::5 IDLE -> FAILURE"] * 2 + ["1 Plan::5 IDLE -> SUCCESS"]
    assert walk_1[-16:] == [
        "1 drive_or_recover IDLE -> RUNNING",
        "1 Drive::7 IDLE -> FAILURE",
        "1 spare IDLE -> FAILURE",
        "1 recover IDLE -> RUNNING",
        "1 recover/Sequence::10 IDLE -> RUNNING",
        "1 recover/Wait2::11 IDLE -> SUCCESS",
        "1 recover/ClearMap::12 IDLE -> SUCCESS",
        "1 recover/Sequence::10 RUNNING -> SUCCESS",
        "1 recover RUNNING -> SUCCESS",
        "1 drive_or_recover RUNNING -> SUCCESS",
        "1 attempt RUNNING -> SUCCESS",
        "1 RetryUntilSuccessful::3 RUNNING -> SUCCESS",
        "1 report_block IDLE -> SUCCESS",
        "1 ForceSuccess::16 IDLE -> RUNNING",
        "1 KeepRunningUntilFailure::17 IDLE -> RUNNING",
        "1 Poll::18 IDLE -> SUCCESS",  # polls 1: the loop goes on at the next tick; the third poll fails it
    ]
    assert [t["path"] for t in result["transitions"] if t["path"].startswith("Beep")] == []


BAD_RULES = {
    '{"SubstitutionRules": {"Plan": "Works"}, "TestNodeConfigs": {"Works": {"return_staus": "SUCCESS"}}}':
        ":1: TestNodeConfig 'Works' has an unknown key 'return_staus' (its keys: return_status, return_status_script, "
        "async_delay, success_script, failure_script, post_script); did you mean 'return_status'?",
    '{\n "TestNodeConfigs": {"A": {"return_status": "SUCCESS", "async_delay": -5}},\n "SubstitutionRules": {}\n}':
        ":2: TestNodeConfig 'A': async_delay must be a whole number of milliseconds from 0 to 2147483647, got the "
        "number -5",
    '{"SubstitutionRules": {"Plan": "A", "Plan": "B"}}':
        ":1: the key 'Plan' is given twice (first at line 1); BT.CPP would keep the last silently",
    '{"TestNodeConfigs": {"A": {"return_status": "DONE"}}, "SubstitutionRules": {}}':
        ":1: TestNodeConfig 'A': return_status 'DONE' is not one of RUNNING, SUCCESS, FAILURE, SKIPPED",
    '{"TestNodeConfigs": {"A": {"post_script": "x := 1"}}, "SubstitutionRules": {}}':
        ":1: TestNodeConfig 'A' must contain return_status or return_status_script",
    '{"SubstitutionRules": {"Plan": "Nothing"}}':
        ":1: rule 'Plan': 'Nothing' is neither a TestNodeConfig of this file nor a registered node type",
    '{"SubstitutionRules": {"Plan": "Sequence"}}':
        ":1: rule 'Plan': Sequence is Control; only an action or a condition (or a TestNodeConfig) can replace a node",
    '{"SubstitutionRules": [1, 2]}': ":1: SubstitutionRules must be a JSON object, got a list",
    '{"SubstitutionRules": {"Plan": "A"},}': ":1: not valid JSON: expected a key in double quotes",
    "[" * 100: ":1: not valid JSON: nested deeper than 8 levels",
    '{"SubstitutionRules": {"Plan": ' + "9" * 5000 + "}}": ":1: not valid JSON: a number of 5000 characters",
    '{"SubstitutionRules": {' + ", ".join(f'"k{i}": "AlwaysSuccess"' for i in range(10_001)) + "}}":
        ":1: holds more than 10,000 rules or TestNodeConfigs",
    '{"TestNodeConfigs": {"A": {"return_status_script": "x :="}}, "SubstitutionRules": {}}':
        ":1: TestNodeConfig 'A': return_status_script: script 'x :=': expected an operand (got 'end of script') at "
        "column 5",
    '{"SubstitutionRules": {"Plan\x07": "A"}}': ":1: not valid JSON: a control character inside text",
}


@pytest.mark.parametrize("text", list(BAD_RULES), ids=range(len(BAD_RULES)))
def test_a_hostile_rule_file_is_one_sentence_at_its_line(text: str, tmp_path: Path,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    tree = write(tmp_path, "t.xml", MODEL_TREE.replace("ReadBattery", "Plan"))
    rules = write(tmp_path, "r.json", text)
    code, out, err = run_cli(capsys, "tree", "run", "--dry", tree, "--substitution-rules", rules)
    assert (code, out, err) == (2, "", f"bt-grasp: error: {rules}{BAD_RULES[text]}\n")


def test_overlapping_rules_apply_the_first_in_the_file_and_say_so(tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    tree = write(tmp_path, "t.xml", MODEL_TREE)
    rules = write(tmp_path, "r.json", '{"TestNodeConfigs": {"F": {"return_status": "FAILURE"}},\n'
                                      ' "SubstitutionRules": {\n  "Read*": "F",\n  "ReadBattery": "AlwaysSuccess",\n'
                                      '  "Nowhere": "F"\n }\n}')
    code, out, err = run_cli(capsys, "tree", "run", "--dry", tree, "--substitution-rules", rules)
    assert code == 1 and "[0.000]: ReadBattery::2            IDLE -> FAILURE" in out  # "Read*" came first
    assert err.splitlines() == [
        f"bt-grasp: warning: {rules}: rules 'Read*' (line 3) and 'ReadBattery' (line 4) all match ReadBattery::2; the "
        "first in the file applies (BT.CPP keeps its rules in an unordered map: which one it applies is unspecified)",
        f"bt-grasp: warning: {rules}:5: rule 'Nowhere' matches no node of this tree",
    ]


# ---- 4. a stand-in wrote none of its output ports: a tree checking error_code_id failed in one tick -----------
def test_a_stand_in_writes_its_output_ports(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tree = write(tmp_path, "plan.xml", """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <RetryUntilSuccessful num_attempts="3">
      <Sequence>
        <ComputePath error_code_id="{error}"/>
        <ScriptCondition code="error == 0"/>
      </Sequence>
    </RetryUntilSuccessful>
  </BehaviorTree>
  <TreeNodesModel>
    <Action ID="ComputePath"><output_port name="error_code_id" type="uint16"/></Action>
  </TreeNodesModel>
</root>
""")
    # by default the stand-in writes its type's default (0), at SUCCESS and at FAILURE alike
    code, out, err = run_cli(capsys, "tree", "run", "--dry", tree, "--json")
    assert (code, err, json.loads(out)["blackboard"]) == (0, "", {"error": 0})
    # a value given per call: 204 the first time (the check fails, the retry runs again), then 0
    code, out, err = run_cli(capsys, "tree", "run", "--dry", tree, "--output-port", "ComputePath.error_code_id=204,0",
                             "--json")
    result = json.loads(out)
    assert (code, err, result["blackboard"]) == (0, "", {"error": 0})
    assert [m for m in moves(result) if "-> IDLE" not in m and "Sequence" not in m and "Retry" not in m] == [
        "1 ComputePath::3 IDLE -> SUCCESS", "1 ScriptCondition::4 IDLE -> FAILURE",
        "1 ComputePath::3 IDLE -> SUCCESS", "1 ScriptCondition::4 IDLE -> SUCCESS",
    ]
    code, _, err = run_cli(capsys, "tree", "run", "--dry", tree, "--output-port", "ComputePath.eror=1")
    assert code == 2 and err == ("bt-grasp: error: --output-port 'ComputePath.eror=1': ComputePath has no output port "
                                 "'eror' (its output ports: error_code_id)\n")
    code, _, err = run_cli(capsys, "tree", "run", "--dry", tree, "--output-port", "ComputePath.error_code_id=lots")
    assert code == 2 and "'lots' is not a int for port 'error_code_id'" in err


# ---- 5. tree run had no --set to seed the blackboard (Nav2 sets goal before the first tick) --------------------
PLUGIN = '''
from dataclasses import dataclass

from bt_grasp.nodes import Leaf, NodeRegistry, Status, action, input_port


@dataclass(frozen=True)
class Goal:
    x: float
    y: float

    @classmethod
    def from_port_text(cls, text: str) -> "Goal":
        x, y = text.split(";")
        return cls(float(x), float(y))


@action(ports=[input_port("goal", Goal)])
class CheckGoal(Leaf):
    def update(self) -> Status:
        goal = self.ports.get("goal", Goal)
        return Status.SUCCESS if goal == Goal(3.0, 0.0) else Status.FAILURE


def register(registry: NodeRegistry) -> None:
    registry.register(CheckGoal)
'''


def test_set_seeds_the_blackboard_before_the_first_tick(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    plugin = write(tmp_path, "goal_nodes.py", PLUGIN)
    tree = write(tmp_path, "goal.xml", '<root BTCPP_format="4"><BehaviorTree ID="M"><CheckGoal goal="{goal}"/>'
                                       "</BehaviorTree></root>")
    assert run_cli(capsys, "tree", "run", "--dry", "--leaves", plugin, tree)[0] == 1  # no goal yet
    code, out, _ = run_cli(capsys, "tree", "run", "--dry", "--leaves", plugin, tree, "--set", "goal=3;0")
    assert code == 0 and "[0.000]: CheckGoal::1              IDLE -> SUCCESS" in out  # the text read as a Goal


# ---- 6. --substitute 'Clear*=AlwaysFailure' was silently a no-op ----------------------------------------------
def test_a_wildcard_reaches_other_projects_leaves_and_one_matching_nothing_is_an_error(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tree = write(tmp_path, "clear.xml", """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Fallback><ClearEntireCostmap name="ClearLocal"/><Script code="cleared := false"/></Fallback>
  </BehaviorTree>
  <TreeNodesModel><Action ID="ClearEntireCostmap"/></TreeNodesModel>
</root>
""")
    code, out, err = run_cli(capsys, "tree", "run", "--dry", tree, "--substitute", "Clear*=AlwaysFailure", "--json")
    result = json.loads(out)
    assert (code, err, result["blackboard"]) == (0, "", {"cleared": False})  # the stand-in was replaced: it failed
    assert "1 ClearLocal IDLE -> FAILURE" in moves(result)
    for flag, value, sentence in (
        ("--substitute", "Clean*=AlwaysFailure", "--substitute 'Clean*=AlwaysFailure': replaces no leaf of this tree "
         "(a wildcard reaches the robot's leaves and those a plugin or TreeNodesModel brought; name another leaf "
         "exactly)"),
        ("--outcome", "Clean*=failure", "--outcome 'Clean*=failure': the pattern 'Clean*' matches no leaf of this tree "
         "(by type, name or full path; stand-ins: ClearEntireCostmap)"),
        ("--outcome", "ClearLocl=failure", "--outcome 'ClearLocl=failure': the name 'ClearLocl' matches no leaf of "
         "this tree (by type, name or full path; stand-ins: ClearEntireCostmap); did you mean 'ClearLocal'?"),
    ):
        code, out, err = run_cli(capsys, "tree", "run", "--dry", tree, flag, value)
        assert (code, out, err) == (2, "", f"bt-grasp: error: {sentence}\n")


# ---- 7. the walk was grouped by node in tree order: a RecoveryNode's loop lost its order, halts were not shown,
#         and a dry run could not write a .btlog ----------------------------------------------------------------
def test_the_walk_is_every_change_in_order_with_halts_and_a_btlog(tmp_path: Path,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    from bt_grasp.recording.btlog import read_btlog

    tree = write(tmp_path, "guarded.xml", """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Fallback name="drive_or_stop">
      <ReactiveSequence name="guarded"><Safe/><Drive/></ReactiveSequence>
      <Stop/>
    </Fallback>
  </BehaviorTree>
  <TreeNodesModel><Condition ID="Safe"/><Action ID="Drive"/><Action ID="Stop"/></TreeNodesModel>
</root>
""")
    btlog = tmp_path / "guarded.btlog"
    code, out, err = run_cli(capsys, "tree", "run", "--dry", tree, "--outcome", "Safe=success,success,failure",
                             "--outcome", "Drive=running:5", "--export-btlog", str(btlog))
    assert (code, err) == (0, "") and walk(out) == [
        "tick 1: RUNNING",
        "[0.000]: drive_or_stop             IDLE -> RUNNING",
        "[0.000]: guarded                   IDLE -> RUNNING",
        "[0.000]: Safe::3                   IDLE -> SUCCESS",
        "[0.000]: Drive::4                  IDLE -> RUNNING",
        "[0.000]: Safe::3                   SUCCESS -> IDLE",  # the reactive sequence resets what came before
        "tick 2: RUNNING",
        "[0.010]: Safe::3                   IDLE -> SUCCESS",
        "[0.010]: Safe::3                   SUCCESS -> IDLE",
        "tick 3: SUCCESS",
        "[0.020]: Safe::3                   IDLE -> FAILURE",  # the third call fails ...
        "[0.020]: Safe::3                   FAILURE -> IDLE",
        "[0.020]: Drive::4                  RUNNING -> IDLE",  # ... and the RUNNING Drive is halted
        "[0.020]: guarded                   RUNNING -> FAILURE",
        "[0.020]: Stop::5                   IDLE -> SUCCESS",
        "[0.020]: guarded                   FAILURE -> IDLE",
        "[0.020]: Stop::5                   SUCCESS -> IDLE",
        "[0.020]: drive_or_stop             RUNNING -> SUCCESS",
        "[0.020]: drive_or_stop             SUCCESS -> IDLE",
        f"wrote 16 transitions to {btlog}",
    ]
    log = read_btlog(btlog)  # Groot2's FileLogger2 format, the writer replay --export-btlog uses
    paths = {uid: node["fullpath"] for uid, node in log.nodes.items()}
    assert [(t.timestamp_us, paths[t.uid], t.status) for t in log.transitions][9:12] == [
        (20_000, "Drive::4", "IDLE"), (20_000, "guarded", "FAILURE"), (20_000, "Stop::5", "SUCCESS")]


def test_a_recovery_loop_within_one_tick_keeps_its_order(capsys: pytest.CaptureFixture[str]) -> None:
    """Nav2's navigate_to_pose_w_replanning_and_recovery.xml, its leaves stood in for from Nav2's model, outcomes from
    a substitution-rule file, Nav2's controls from a plugin (done when, item 2): the recoveries in turn, in one tick,
    in BT.CPP's order (tests/tree_conformance/rules/nav2_recoveries_in_one_tick.btcpp.json is BT.CPP's own walk)."""
    nav2_tree = str(NAV2 / "navigate_to_pose_w_replanning_and_recovery.xml")
    code, out, err = run_cli(capsys, "tree", "run", "--dry", nav2_tree, "--nodes-model",
                             str(NAV2 / "nav2_tree_nodes.xml"), "--leaves", str(NAV2 / "nav2_controls.py"),
                             "--substitution-rules",
                             str(RULES / "nav2_recoveries_in_one_tick.rules.json"), "--set", "plans=0", "--set",
                             "follows=0", "--json")
    result = json.loads(out)
    assert (code, err, result["status"], result["ticks"]) == (0, "", "SUCCESS", 1)
    leaves = ("ComputePathToPose::17", "FollowPath::22", "Context", "Subtree", "Spin::36", "Wait::37", "BackUp::38")
    done = [f"{m['path']} {m['to']}" for m in result["transitions"]
            if m["from"] == "IDLE" and m["to"] != "RUNNING" and m["path"].endswith(leaves)]
    assert done == [
        "ComputePathToPose::17 FAILURE", "ClearGlobalCostmap-Context SUCCESS", "ComputePathToPose::17 SUCCESS",
        "FollowPath::22 FAILURE", "ClearLocalCostmap-Context SUCCESS", "FollowPath::22 FAILURE",
        "ClearLocalCostmap-Subtree SUCCESS", "ClearGlobalCostmap-Subtree SUCCESS",  # RoundRobin's turn 1: clearing
        "ComputePathToPose::17 SUCCESS", "FollowPath::22 FAILURE", "ClearLocalCostmap-Context SUCCESS",
        "FollowPath::22 FAILURE", "Spin::36 SUCCESS",  # turn 2
        "ComputePathToPose::17 SUCCESS", "FollowPath::22 FAILURE", "ClearLocalCostmap-Context SUCCESS",
        "FollowPath::22 FAILURE", "Wait::37 SUCCESS",  # turn 3
        "ComputePathToPose::17 SUCCESS", "FollowPath::22 FAILURE", "ClearLocalCostmap-Context SUCCESS",
        "FollowPath::22 SUCCESS",  # the eighth follow arrives
    ]
    expected = json.loads((RULES / "nav2_recoveries_in_one_tick.btcpp.json").read_text())
    assert [[m["tick"], m["path"], m["from"], m["to"]] for m in result["transitions"]] == expected["transitions"]


# ---- 8. tree validate reported only the first unknown node; the README's tree run line omitted options ---------
def test_validate_names_every_unknown_node(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tree = write(tmp_path, "nav.xml", MODEL_TREE.replace("<ScriptCondition", "<Dock/>\n      <ScriptCondtion"))
    code, out, err = run_cli(capsys, "tree", "validate", tree)
    model = "the TreeNodesModel at {0}:{1} declares it, but no plugin gives its code (`bt-grasp tree run --dry` " \
            "stands in for it; `bt-grasp tree stubs` writes a plugin to start from)"
    assert (code, out) == (2, "") and err.splitlines() == [
        f"bt-grasp: error: {tree}:4: unknown node 'ReadBattery': {model.format(tree, 11)}",
        f"bt-grasp: error: {tree}:5: unknown node 'IsCharged': {model.format(tree, 15)}",
        f"bt-grasp: error: {tree}:6: unknown node 'Dock'",
        f"bt-grasp: error: {tree}:7: unknown node 'ScriptCondtion'; did you mean 'ScriptCondition'?",
    ]


def test_the_readme_lists_every_option_of_tree_run() -> None:
    from bt_grasp.cli.tree_cmd import run_cmd

    readme = (REPO / "README.md").read_text()
    (line,) = [line for line in readme.splitlines() if line.startswith("| `bt-grasp tree run FILE")]
    synopsis = line.split("`")[1]
    import inspect

    import typer

    options = [p.default for p in inspect.signature(run_cmd).parameters.values() if isinstance(p.default,
                                                                                               typer.models.OptionInfo)]
    names = {name for option in options for name in option.param_decls if name.startswith("--")}
    assert {"--outcome", "--random", "--tick-hz", "--nodes-model", "--substitution-rules", "--output-port",
            "--export-btlog", "--scene", "--set"} <= names
    assert [name for name in sorted(names) if name not in synopsis] == []


# ---- issue 43, finding 10: a tree checked against its scene ---------------------------------------------------
def test_validate_checks_a_tree_against_its_scene(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scene = str(REPO / "scenes" / "sort_by_color.yaml")
    tree = write(tmp_path, "sort.xml", """<root BTCPP_format="4" main_tree_to_execute="T">
  <BehaviorTree ID="T">
    <Sequence>
      <FixturePose fixture="left_trey" pose="{place_pose}"/>
      <PerceiveAll objects="{objects}"/>
      <SelectObject objects="{objects}" color="purple" object="{object}"/>
    </Sequence>
  </BehaviorTree>
</root>
""")
    assert run_cli(capsys, "tree", "validate", tree)[0] == 0  # without a scene, nothing to check a name against
    code, out, err = run_cli(capsys, "tree", "validate", tree, "--scene", scene)
    assert (code, out) == (2, "") and err == (
        f"bt-grasp: error: {tree}:4: FixturePose: no fixture named 'left_trey' in the scene (fixtures: left_tray, "
        "right_tray); did you mean 'left_tray'?\n")
    Path(tree).write_text(Path(tree).read_text().replace("left_trey", "left_tray"))
    code, out, err = run_cli(capsys, "tree", "validate", tree, "--scene", scene)
    assert (code, out) == (0, f"{tree}: OK (4 nodes, main tree T, fits {scene})\n")
    assert err == (f"bt-grasp: warning: {tree}:6: SelectObject 'SelectObject::4' looks for the colour 'purple', which "
                   f"no object of {scene} has (its objects' colours: blue, red)\n")


def test_the_dry_runs_fixture_pose_comes_from_the_scene(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tree = write(tmp_path, "fixture.xml", '<root BTCPP_format="4"><BehaviorTree ID="T"><Sequence>'
                 '<FixturePose fixture="right_tray" slot="{slot}" pose="{place_pose}"/></Sequence></BehaviorTree>'
                 "</root>")
    scene = str(REPO / "scenes" / "sort_by_color.yaml")
    code, out, _ = run_cli(capsys, "tree", "run", "--dry", tree, "--json", "--set", "slot=-1")
    pose = json.loads(out)["blackboard"]["place_pose"]
    assert code == 0 and (pose["x_m"], pose["y_m"]) == (0.45, -0.25)  # without a scene: a fixed pose
    code, out, _ = run_cli(capsys, "tree", "run", "--dry", tree, "--json", "--set", "slot=-1", "--scene", scene)
    # right_tray's centre (0.30, -0.49) and its floor's height, in the base frame (here the world's), as the real
    # FixturePose computes it from the scene
    pose = json.loads(out)["blackboard"]["place_pose"]
    assert code == 0 and (pose["x_m"], pose["y_m"], pose["z_m"], pose["frame"]) == (0.30, -0.49, 0.004, "base")
    # a slot the tray lacks: the stand-in fails as the real leaf would
    code, out, _ = run_cli(capsys, "tree", "run", "--dry", tree, "--json", "--set", "slot=40", "--scene", scene)
    result = json.loads(out)
    assert code == 1 and result["blackboard"]["failure_reason"] == "BAD_INPUT"
