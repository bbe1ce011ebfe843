"""`--leaves` on the tree commands: users' nodes validate, run dry and appear in `tree models`; a bad plugin is
exit 2 with one sentence naming the file (and line) and the problem, never a traceback."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bt_grasp.cli.main import main

PLUGIN = Path(__file__).parent / "data" / "user_nodes.py"

TREE = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence>
      <Fallback>
        <CheckWeight grams="750"/>
        <Sequence>
          <FailureIs reason="WEIGHT_OUT_OF_RANGE" leaf="CheckWeight"/>
          <Script code="verdict := 'rejected'"/>
        </Sequence>
      </Fallback>
      <RateLimit period_msec="20">
        <RoundRobinFallback><AlwaysFailure/><WaitSim seconds="0.03"/></RoundRobinFallback>
      </RateLimit>
    </Sequence>
  </BehaviorTree>
</root>
"""


@pytest.fixture
def tree_file(tmp_path: Path) -> Path:
    path = tmp_path / "weigh.xml"
    path.write_text(TREE)
    return path


def _one_line_error(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("bt-grasp: error: "), err  # the one error format of every command
    return lines[0].removeprefix("bt-grasp: error: ")


def test_validate_needs_the_plugin_and_passes_with_it(tree_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tree", "validate", str(tree_file)]) == 2
    # every node the plugin would bring is named, each at its line (one line each)
    assert capsys.readouterr().err.splitlines() == [
        f"bt-grasp: error: {tree_file}:5: unknown node 'CheckWeight'",
        f"bt-grasp: error: {tree_file}:11: unknown node 'RateLimit'",
        f"bt-grasp: error: {tree_file}:12: unknown node 'RoundRobinFallback'; did you mean 'Fallback'?",
        f"bt-grasp: error: {tree_file}:12: unknown node 'WaitSim'",
    ]
    assert main(["tree", "validate", "--leaves", str(PLUGIN), str(tree_file)]) == 0
    assert capsys.readouterr().out.strip() == f"{tree_file}: OK (10 nodes, main tree Main)"


def test_dry_run_with_the_plugin(tree_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # tick 1 (t=0): CheckWeight fails with WEIGHT_OUT_OF_RANGE, FailureIs matches, verdict set; RateLimit lets
    # its child start: AlwaysFailure fails, WaitSim (deadline t=30 ms) RUNNING; ticks 2-3 RUNNING; tick 4 SUCCESS
    code = main(["tree", "run", "--dry", "--json", "--leaves", str(PLUGIN), str(tree_file)])
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    assert out["status"] == "SUCCESS" and out["ticks"] == 4
    assert out["blackboard"]["verdict"] == "rejected"  # FailureIs matched WEIGHT_OUT_OF_RANGE
    assert "failure_reason" not in out["blackboard"]  # the tree succeeded: the recovered failure is cleared


def test_models_list_the_users_nodes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tree", "models", "--leaves", str(PLUGIN)]) == 0
    text = capsys.readouterr().out
    for tag in ('<Condition ID="CheckWeight"', '<Action ID="WaitSim"', '<Control ID="RoundRobinFallback"',
                '<Decorator ID="RateLimit"'):
        assert tag in text
    assert 'name="max_grams"' in text and 'default="500.000000"' in text
    assert main(["tree", "models"]) == 0
    assert "CheckWeight" not in capsys.readouterr().out


def test_unknown_reason_in_failure_is_is_a_load_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "typo.xml"
    path.write_text(TREE.replace('reason="WEIGHT_OUT_OF_RANGE"', 'reason="WEIGHT_OUT_OF_RANG"'))
    assert main(["tree", "validate", "--leaves", str(PLUGIN), str(path)]) == 2
    assert _one_line_error(capsys) == (
        f"{path}:7: FailureIs: unknown failure reason 'WEIGHT_OUT_OF_RANG'; did you mean 'WEIGHT_OUT_OF_RANGE'?"
    )


def test_a_user_reason_without_its_plugin_is_unknown(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "alone.xml"
    path.write_text('<root BTCPP_format="4"><BehaviorTree ID="M"><Fallback><AlwaysFailure/>\n'
                    '<FailureIs reason="WEIGHT_OUT_OF_RANGE"/></Fallback></BehaviorTree></root>')
    assert main(["tree", "validate", str(path)]) == 2
    assert _one_line_error(capsys).startswith(f"{path}:2: FailureIs: unknown failure reason 'WEIGHT_OUT_OF_RANGE'")


HEADER = "from bt_grasp.nodes import Leaf, NodeRegistry, Reason, Status, action, input_port\n"
GOOD_LEAF = "@action()\nclass Beep(Leaf):\n    def update(self):\n        return Status.SUCCESS\n"

BAD_PLUGINS = {
    "syntax": (HEADER + "def register(registry:\n", 2, "import error: syntax error: '(' was never closed"),
    "import": ("import no_such_module_for_bt_grasp\n", 1,
               "import error: ModuleNotFoundError: No module named 'no_such_module_for_bt_grasp'"),
    "raises": (HEADER + "x = 1 / 0\n", 2, "import error: ZeroDivisionError: division by zero"),
    "no_register": (HEADER + GOOD_LEAF, None, "defines no register(registry) function (see docs/own-leaves.md)"),
    "duplicate_builtin": (
        HEADER + "@action(name='Sequence')\nclass Mine(Leaf):\n    pass\n"
        "def register(registry: NodeRegistry) -> None:\n    registry.register(Mine)\n",
        6, "bad declaration: a node named 'Sequence' is already registered by bt_grasp "
        "(to replace it, call registry.unregister('Sequence') first)"),
    "duplicate_robot_leaf": (
        HEADER + "@action(name='Perceive')\nclass Mine(Leaf):\n    pass\n"
        "def register(registry: NodeRegistry) -> None:\n    registry.register(Mine)\n",
        6, "bad declaration: a node named 'Perceive' is already registered by bt_grasp "
        "(to replace it, call registry.unregister('Perceive') first)"),
    "old_register_of_a_spec": (
        HEADER + "@action()\nclass Mine(Leaf):\n    pass\n"
        "def register(registry: NodeRegistry) -> None:\n    registry.register(Mine.bt_spec)\n",
        6, "bad declaration: register() takes the node class, not its spec: registry.register(Mine) (BT.CPP's "
           "registerNodeType<T>)"),
    "undeclared_class": (
        HEADER + "class Mine(Leaf):\n    pass\n"
        "def register(registry: NodeRegistry) -> None:\n    registry.register(Mine)\n",
        5, "bad declaration: Mine is not declared: decorate the class with @action(...), @condition(...), "
           "@control(...) or @decorator(...) from bt_grasp.nodes (its manifest, as BT.CPP's providedPorts)"),
    "duplicate_reason": (
        HEADER + "def register(registry: NodeRegistry) -> None:\n    registry.register_reason(Reason('SLIPPED'))\n",
        3, "bad declaration: a failure reason named 'SLIPPED' is already registered by bt_grasp"),
    "bad_reason_name": (
        HEADER + "def register(registry: NodeRegistry) -> None:\n    registry.register_reason('too heavy')\n",
        3, "bad declaration: failure reason 'too heavy' must be upper-case letters, digits and underscores, "
           "starting with a letter (at most 64 characters)"),
    "bad_port_type": (
        HEADER + "@action(ports=[input_port('items', 'list')])\nclass Mine(Leaf):\n    pass\n",
        2, "bad declaration: port 'items': type must be a class (str, int, float, bool, object or your own), got "
           "'list'"),
    "default_none": (
        HEADER + "@action(ports=[input_port('start', float, None)])\nclass Mine(Leaf):\n    pass\n",
        2, "bad declaration: port 'start': default=None: leave the default out (a port declared without one is "
           "optional, as in BT.CPP; ports.get() returns None while unset)"),
    "reserved_port": (
        HEADER + "@action(ports=[input_port('name')])\nclass Mine(Leaf):\n    pass\n",
        2, "bad declaration: port name 'name' is reserved or not letters, digits and underscores"),
    "bad_reason_at_import": (
        HEADER + "TOO_HEAVY = Reason('too-heavy', 'Heavier than allowed.')\n",
        2, "bad declaration: failure reason 'too-heavy' must be upper-case letters, digits and underscores, "
           "starting with a letter (at most 64 characters)"),
    "register_value_error": (
        HEADER + "def register(registry: NodeRegistry) -> None:\n    int('many')\n",
        3, "register() failed: ValueError: invalid literal for int() with base 10: 'many'"),
    "register_fails": (
        HEADER + "def register(registry: NodeRegistry) -> None:\n    registry.register({}['x'])\n",
        3, "register() failed: KeyError: 'x'"),
    "not_a_spec": (
        HEADER + "def register(registry: NodeRegistry) -> None:\n    registry.register('Beep')\n",
        3, "bad declaration: register() takes a node class declared with @action(...), @condition(...), "
           "@control(...) or @decorator(...) (BT.CPP's registerNodeType<T>), got 'Beep'"),
}


@pytest.mark.parametrize("case", sorted(BAD_PLUGINS))
def test_bad_plugin_is_exit_2_with_one_sentence(
    case: str, tree_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text, line, problem = BAD_PLUGINS[case]
    bad = tmp_path / "bad.py"
    bad.write_text(text)
    assert main(["tree", "validate", "--leaves", str(bad), str(tree_file)]) == 2
    where = f":{line}" if line else ""
    assert _one_line_error(capsys) == f"{bad}{where}: {problem}"


def test_the_same_plugin_twice_names_the_duplicate(tree_file: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tree", "validate", "--leaves", str(PLUGIN), "--leaves", str(PLUGIN), str(tree_file)]) == 2
    line = PLUGIN.read_text().splitlines().index("    registry.register_reason(WEIGHT_OUT_OF_RANGE)") + 1
    assert _one_line_error(capsys) == (
        f"{PLUGIN}:{line}: bad declaration: a failure reason named 'WEIGHT_OUT_OF_RANGE' is already registered by "
        f"{PLUGIN}"
    )


@pytest.mark.parametrize(
    ("value", "problem"),
    [
        ("missing_leaves.py", "missing_leaves.py: no such plugin file"),
        ("no_such_pkg_for_bt_grasp.nodes", "no_such_pkg_for_bt_grasp.nodes: import error: ModuleNotFoundError: "
                                           "No module named 'no_such_pkg_for_bt_grasp'"),
        ("not a module", "not a module: is neither a .py file nor a module name such as my_pkg.nodes"),
    ],
)
def test_missing_plugins(value: str, problem: str, tree_file: Path, tmp_path: Path,
                         monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["tree", "validate", "--leaves", value, str(tree_file)]) == 2
    assert _one_line_error(capsys) == problem


def test_a_plugin_module_by_name(tree_file: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                 capsys: pytest.CaptureFixture[str]) -> None:
    package = tmp_path / "weighing"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "nodes.py").write_text(PLUGIN.read_text())
    monkeypatch.syspath_prepend(str(tmp_path))
    assert main(["tree", "validate", "--leaves", "weighing.nodes", str(tree_file)]) == 0


@pytest.mark.parametrize("command", [
    ["tree", "show"], ["tree", "run", "--dry"], ["tree", "models"], ["tree", "convert"],
])
def test_every_tree_command_takes_leaves(command: list[str], tree_file: Path, tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.py"
    bad.write_text("import no_such_module_for_bt_grasp\n")
    args = [*command, "--leaves", str(bad)]
    if command[1] != "models":
        args.append(str(tree_file))
    if command[1] == "convert":
        args.append(str(tmp_path / "out.yaml"))
    assert main(args) == 2
    assert _one_line_error(capsys).startswith(f"{bad}:1: import error: ModuleNotFoundError")


def test_show_and_convert_with_the_plugin(tree_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tree", "show", "--format", "dot", "--leaves", str(PLUGIN), str(tree_file)]) == 0
    dot = capsys.readouterr().out
    assert "RoundRobinFallback" in dot and "RateLimit" in dot and "CheckWeight" in dot
    yaml_file = tmp_path / "weigh.yaml"
    assert main(["tree", "convert", "--leaves", str(PLUGIN), str(tree_file), str(yaml_file)]) == 0
    capsys.readouterr()
    assert main(["tree", "validate", "--leaves", str(PLUGIN), str(yaml_file)]) == 0  # the YAML twin loads too
