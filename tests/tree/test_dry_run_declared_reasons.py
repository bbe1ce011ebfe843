"""A dry run's stand-in fails with the reasons its leaf declares (issue 24): ``@action(reasons=[...])`` on a user's
plugin leaf, ``NodeSpec.failure_reasons`` for every leaf, no table to edit. On main as it was the reasons came from
a hand table of the built-in leaves (``bt_grasp.behaviours.stand_ins.FAILURE_REASONS``): a plugin leaf told to fail
failed with no reason (so ``FailureIs`` never matched it), any known reason was accepted for it, and ``--random``
drew among every reason bt_grasp knows."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bt_grasp.cli.main import main

PLUGIN = '''"""A user's plugin leaf that declares its own failure reasons."""

from bt_grasp.nodes import FailureReason, NodeRegistry, Reason, RobotLeaf, Status, action, input_port

SCALE_OVERLOAD = Reason("SCALE_OVERLOAD", "The object is heavier than the gripper may lift.")


@action(ports=[input_port("max_kg", float, 1.0, "heaviest object to lift, kg")], needs_robot=True,
        reasons=[SCALE_OVERLOAD, FailureReason.TIMEOUT])
class CheckWeight(RobotLeaf):
    """Weighs the held object with the wrist's force sensor."""

    def update(self) -> Status:
        return Status.SUCCESS


def register(registry: NodeRegistry) -> None:
    registry.register_reason(SCALE_OVERLOAD)
    registry.register(CheckWeight)
'''

TREE = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Fallback>
      <CheckWeight max_kg="1.0"/>
      <Sequence name="overload">
        <FailureIs reason="SCALE_OVERLOAD" leaf="CheckWeight"/>
        <SetBlackboard output_key="handled" value="overload"/>
      </Sequence>
    </Fallback>
  </BehaviorTree>
</root>
"""


@pytest.fixture
def files(tmp_path: Path) -> tuple[str, str]:
    (tmp_path / "weigh.py").write_text(PLUGIN)
    (tmp_path / "weigh.xml").write_text(TREE)
    return str(tmp_path / "weigh.py"), str(tmp_path / "weigh.xml")


def _dry(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(["tree", "run", "--dry", *args])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_a_plugin_leaf_told_to_fail_fails_with_its_first_declared_reason(
    files: tuple[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    plugin, tree = files
    code, out, err = _dry(capsys, "--leaves", plugin, tree, "--outcome", "CheckWeight=failure", "--json")
    assert code == 0, err
    result = json.loads(out)
    assert result["blackboard"]["handled"] == "overload"  # FailureIs matched SCALE_OVERLOAD: the recovery ran
    assert "failure_reason" not in result["blackboard"]  # the tree succeeded: the reason is cleared
    # tick 1, in order: the leaf failed with its reason, the Fallback's second child handled it
    assert [(t["tick"], t["path"], t["from"], t["to"]) for t in result["transitions"]] == [
        (1, "Fallback::1", "IDLE", "RUNNING"),
        (1, "CheckWeight::2", "IDLE", "FAILURE"),
        (1, "overload", "IDLE", "RUNNING"),
        (1, "FailureIs::4", "IDLE", "SUCCESS"),
        (1, "SetBlackboard::5", "IDLE", "SUCCESS"),
        (1, "FailureIs::4", "SUCCESS", "IDLE"),
        (1, "SetBlackboard::5", "SUCCESS", "IDLE"),
        (1, "overload", "RUNNING", "SUCCESS"),
        (1, "CheckWeight::2", "FAILURE", "IDLE"),
        (1, "overload", "SUCCESS", "IDLE"),
        (1, "Fallback::1", "RUNNING", "SUCCESS"),
        (1, "Fallback::1", "SUCCESS", "IDLE"),
    ]


def test_a_reason_the_plugin_leaf_does_not_declare_is_refused(
    files: tuple[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    plugin, tree = files
    code, out, err = _dry(capsys, "--leaves", plugin, tree, "--outcome", "CheckWeight=failure:NO_FRAME")
    assert (code, out) == (2, "")
    assert err == ("bt-grasp: error: --outcome 'CheckWeight=failure:NO_FRAME': CheckWeight does not fail with "
                   "NO_FRAME; it declares SCALE_OVERLOAD, TIMEOUT\n")
    code, _, err = _dry(capsys, "--leaves", plugin, tree, "--outcome", "CheckWeight=failure:TIMEOUT")
    assert code == 1, err  # a declared built-in reason: FailureIs SCALE_OVERLOAD does not match it


def test_random_mode_draws_only_the_declared_reasons(
    files: tuple[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    plugin, tree = files
    seen: set[str | None] = set()
    for seed in range(24):
        code, out, err = _dry(capsys, "--leaves", plugin, tree, "--random", str(seed), "--json")
        assert code in (0, 1), err
        blackboard = json.loads(out)["blackboard"]  # a recovered failure's reason is cleared with the success
        seen.add("SCALE_OVERLOAD" if blackboard.get("handled") else blackboard.get("failure_reason"))
    assert seen == {None, "SCALE_OVERLOAD", "TIMEOUT"}  # success, or one of the two it declares


def test_a_leaf_declaring_an_unregistered_reason_is_a_bad_plugin(
    tmp_path: Path, files: tuple[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    _, tree = files
    bad = tmp_path / "bad.py"
    # the reason named by text only, never declared as a Reason value nor registered
    bad.write_text(PLUGIN.replace("    registry.register_reason(SCALE_OVERLOAD)\n", "").replace(
        "reasons=[SCALE_OVERLOAD,", 'reasons=["SCALE_OVERLOAD",'))
    code, out, err = _dry(capsys, "--leaves", str(bad), tree)
    assert (code, out) == (2, "")
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"bt-grasp: error: {bad}:"), err
    assert ("bad declaration: node 'CheckWeight' declares the failure reason 'SCALE_OVERLOAD', which is not "
            "registered") in lines[0]


def test_a_declared_reason_value_is_registered_with_its_node(
    tmp_path: Path, files: tuple[str, str], capsys: pytest.CaptureFixture[str]
) -> None:
    """The declaration is the manifest: a Reason value the leaf declares needs no register_reason call."""
    _, tree = files
    short = tmp_path / "short.py"
    short.write_text(PLUGIN.replace("    registry.register_reason(SCALE_OVERLOAD)\n", ""))
    code, out, err = _dry(capsys, "--leaves", str(short), tree, "--outcome", "CheckWeight=failure", "--json")
    assert code == 0, err
    assert json.loads(out)["blackboard"]["handled"] == "overload"  # FailureIs matched the plugin's reason


def test_every_robot_leaf_declares_registered_reasons_on_its_spec() -> None:
    """The registry's specs carry the reasons (what the dry run reads), every one registered."""
    from bt_grasp.behaviours.library import robot_registry

    registry = robot_registry(installed=False)
    known = {r.name for r in registry.reasons()}
    robot = [s for s in registry.specs() if s.needs_robot]
    assert len(robot) >= 20
    for spec in robot:
        assert spec.failure_reasons and set(spec.failure_reasons) <= known, spec.name
    assert registry["Grasp"].failure_reasons == ("GRASP_EMPTY", "TIMEOUT")
