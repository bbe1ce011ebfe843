"""`bt-grasp tree validate/show/convert/run` through the CLI entry point."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from bt_grasp.bench.tree import tick_overhead
from bt_grasp.cli.main import main

TREE = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence>
      <Script code="attempts := 0"/>
      <RetryUntilSuccessful num_attempts="5">
        <Sequence>
          <Script code="attempts += 1"/>
          <ScriptCondition code="attempts &gt;= 3"/>
        </Sequence>
      </RetryUntilSuccessful>
      <Sleep msec="30"/>
      <SubTree ID="Report" result="{message}"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Report">
    <Script code="result := 'done'"/>
  </BehaviorTree>
</root>
"""


@pytest.fixture
def tree_file(tmp_path: Path) -> Path:
    path = tmp_path / "pick.xml"
    path.write_text(TREE)
    return path


def run_cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_validate_ok(tree_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run_cli(capsys, "tree", "validate", str(tree_file))
    assert code == 0 and "OK (9 nodes, main tree Main)" in out and err == ""


def test_run_dry_json(tree_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "tree", "run", str(tree_file), "--dry", "--json")
    result = json.loads(out)
    # tick 1: retry loops 3 times in one tick, Sleep starts (RUNNING); ticks at 10 ms: Sleep ends at tick 4
    assert code == 0 and [tick["status"] for tick in result.pop("walk")] == ["RUNNING"] * 3 + ["SUCCESS"]
    transitions = result.pop("transitions")
    assert transitions[0] == {"tick": 1, "time_s": 0.0, "path": "Sequence::1", "type": "Sequence", "from": "IDLE",
                              "to": "RUNNING"}
    assert transitions[-1] == {"tick": 4, "time_s": 0.03, "path": "Sequence::1", "type": "Sequence",
                               "from": "SUCCESS", "to": "IDLE"}
    assert result == {"status": "SUCCESS", "ticks": 4, "blackboard": {"attempts": 3, "message": "done"}}


def test_run_not_finished_and_tick_hz(tree_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "tree", "run", str(tree_file), "--dry", "--max-ticks", "2", "--json")
    assert code == 1 and json.loads(out)["status"] == "RUNNING"
    code, out, _ = run_cli(capsys, "tree", "run", str(tree_file), "--dry", "--tick-hz", "20", "--json")
    assert code == 0 and json.loads(out)["ticks"] == 2


def test_run_failure_exit_code(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "fail.yaml"
    path.write_text("trees:\n  Main: AlwaysFailure\n")
    code, out, _ = run_cli(capsys, "tree", "run", str(path), "--dry")
    assert code == 1 and out.startswith("FAILURE after 1 ticks")


def test_run_substitute(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "t.xml"
    path.write_text('<root BTCPP_format="4"><BehaviorTree><Sequence><AlwaysFailure name="Perceive"/>'
                    "</Sequence></BehaviorTree></root>")  # fmt: skip
    code, out, _ = run_cli(capsys, "tree", "run", str(path), "--dry", "--substitute", "Perceive=Running:2", "--json")
    assert code == 0 and json.loads(out)["ticks"] == 3
    code, _, err = run_cli(capsys, "tree", "run", str(path), "--dry", "--substitute", "Perceive")
    assert code == 2 and err.strip().splitlines() == [
        "bt-grasp: error: --substitute: 'Perceive' is not NODE=REPLACEMENT (e.g. Perceive=AlwaysSuccess)"
    ]


def test_run_requires_dry(tree_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run_cli(capsys, "tree", "run", str(tree_file))
    assert code == 2 and err.startswith("bt-grasp: error: --dry:")


def test_show_text_and_dot(tree_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "tree", "show", str(tree_file))
    assert code == 0 and "RetryUntilSuccessful (num_attempts=5)" in out and "SubTree Report" in out
    code, out, _ = run_cli(capsys, "tree", "show", str(tree_file), "--format", "dot")
    assert code == 0 and out.startswith('digraph "Main" {') and "n1 -> n2;" in out
    target = tmp_path / "tree.txt"
    assert run_cli(capsys, "tree", "show", str(tree_file), "--out", str(target))[0] == 0
    assert "Sleep (msec=30)" in target.read_text()


def test_show_image(tree_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    target = tmp_path / "tree.svg"
    code, _out, err = run_cli(capsys, "tree", "show", str(tree_file), "--format", "svg", "--out", str(target))
    if shutil.which("dot") is None:
        assert code == 2 and "Graphviz 'dot' is not installed" in err
    else:
        assert code == 0 and target.read_text().lstrip().startswith("<?xml")


def test_convert_round_trip(tree_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    yaml_path = tmp_path / "pick.yaml"
    assert run_cli(capsys, "tree", "convert", str(tree_file), str(yaml_path))[0] == 0
    code, out, _ = run_cli(capsys, "tree", "run", str(yaml_path), "--dry", "--json")
    assert code == 0 and json.loads(out)["blackboard"] == {"attempts": 3, "message": "done"}
    code, _, err = run_cli(capsys, "tree", "convert", str(tree_file), str(tmp_path / "x.json"))
    assert code == 2 and "unknown tree file extension" in err


def test_missing_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    missing = tmp_path / "nope.xml"
    code, _, err = run_cli(capsys, "tree", "validate", str(missing))
    assert code == 2 and err == f"bt-grasp: error: {missing}: no such file\n"


def test_tick_overhead_reports_microseconds() -> None:
    result = tick_overhead(20, 50)
    assert result["n_nodes"] == 20 and result["n_ticks"] == 50
    # the figures are consistent with each other and in microseconds
    assert result["us_per_tick"] == pytest.approx(result["total_s"] / 50 * 1e6)
    assert result["us_per_node_tick"] == pytest.approx(result["us_per_tick"] / 20)
    # and the tree really was ticked: no py_trees node ticks in under 0.1 us (a loop that skips the ticks takes
    # ~0.05 us an iteration); load only makes it slower, so this floor cannot flake
    assert result["us_per_node_tick"] > 0.1, result


EXAMPLES = sorted((Path(__file__).resolve().parents[2] / "trees" / "builtin_examples").glob("*.*"))


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.name)
def test_builtin_examples_run(example: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run_cli(capsys, "tree", "run", str(example), "--dry", "--json")
    assert code == 0 and json.loads(out)["status"] == "SUCCESS"


def test_run_prints_values_as_btcpp_and_json_keeps_them_typed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "typed.xml"
    path.write_text(
        '<root BTCPP_format="4"><BehaviorTree ID="M">'
        "<Script code=\"half := 6 / 3; n := 4; s := 'i=' .. half\"/></BehaviorTree></root>"
    )
    assert main(["tree", "run", str(path), "--dry"]) == 0
    text = capsys.readouterr().out
    assert "half = 2.000000" in text and "n = 4" in text and "s = i=2.000000" in text
    assert main(["tree", "run", str(path), "--dry", "--json"]) == 0
    blackboard = json.loads(capsys.readouterr().out)["blackboard"]
    assert blackboard == {"half": 2.0, "n": 4, "s": "i=2.000000"} and isinstance(blackboard["half"], float)


def test_models_describe_the_leaves_for_groot2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from bt_grasp.cli.tree_cmd import tree_registry
    from bt_grasp.tree.formats.xml_format import read_xml
    from bt_grasp.tree.validate import check_models

    out = tmp_path / "models.xml"
    assert main(["tree", "models", "--out", str(out)]) == 0
    document = read_xml(out.read_bytes(), str(out))
    names = {m.node_id for m in document.models}
    assert "Approach" in names and "Sequence" not in names  # the leaves, not BT.CPP's built-ins
    check_models(document, tree_registry())  # the models agree with the registry they came from
    assert main(["tree", "models", "--builtins"]) == 0
    assert '<Control ID="ParallelAll">' in capsys.readouterr().out


WARNED = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence>
      <Sleep msec="30ms"/>
      <Sleep msec="30ms"/>
    </Sequence>
  </BehaviorTree>
  <TreeNodesModel>
    <Action ID="Sleep"><input_port name="duration"/></Action>
  </TreeNodesModel>
</root>
"""


def test_validate_shows_each_warning_once_with_its_place(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A tree BT.CPP loads loads here too, but what it ignores is said: one line each, file:line first (the tree
    commands turned these warnings off before, so a user never heard that '30ms' is read as 30)."""
    path = tmp_path / "warned.xml"
    path.write_text(WARNED)
    for _ in range(2):  # a second command in the same process says them again
        code, out, err = run_cli(capsys, "tree", "validate", str(path))
        lines = err.splitlines()
        assert code == 0 and "OK" in out
        assert lines == [
            f"bt-grasp: warning: {path}:9: TreeNodesModel: Sleep has no port 'duration' (its ports: msec)"
            " (BT.CPP ignores it)",
            f"bt-grasp: warning: {path}:4: port 'msec': '30ms' is read as 30, as BT.CPP reads it ('ms' is ignored)",
            f"bt-grasp: warning: {path}:5: port 'msec': '30ms' is read as 30, as BT.CPP reads it ('ms' is ignored)",
        ], lines
