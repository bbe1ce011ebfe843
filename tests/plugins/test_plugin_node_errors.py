"""A user's node that raises (in update, terminate or its constructor) stops a dry run with exit 2 and one
line naming the tree's file and line, the node, the exception and where in the plugin it was raised."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from bt_grasp.cli.main import main

PLUGIN = '''from bt_grasp.nodes import Leaf, Status, action, input_port


@action(ports=[input_port("message", str)])
class Shout(Leaf):
    """Shouts."""

    def update(self) -> Status:
        return self.ports.require("message").shout()


@action()
class Stubborn(Leaf):
    """Cannot be halted."""

    def update(self) -> Status:
        return Status.RUNNING

    def terminate(self, new_status: Status) -> None:
        if new_status is Status.IDLE:
            raise RuntimeError("cannot stop")


@action()
class Unfinished(Leaf):
    """Has no update()."""


def register(registry) -> None:
    for node in (Shout, Stubborn, Unfinished):
        registry.register(node)
'''

TREES = {
    "update": ('<Sequence>\n<Shout message="hi"/>\n</Sequence>', r"tree.xml:4: Shout 'Shout::2': the node's code "
               r"raised AttributeError at .*nodes.py:9: 'str' object has no attribute 'shout'"),
    "init": ("<Unfinished/>", r"tree.xml:3: Unfinished \(from .*nodes.py\) could not be built: TypeError: "),
}


@pytest.mark.parametrize("case", ["update", "init"])
def test_a_raising_user_node_is_one_line_and_exit_2(
    case: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    body, pattern = TREES[case]
    (tmp_path / "nodes.py").write_text(PLUGIN)
    tree = tmp_path / "tree.xml"
    tree.write_text(f'<root BTCPP_format="4">\n<BehaviorTree ID="Main">\n{body}\n</BehaviorTree>\n</root>\n')
    assert main(["tree", "run", str(tree), "--dry", "--leaves", str(tmp_path / "nodes.py")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert re.search(pattern, err), err


def test_a_user_node_raising_while_halted_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "nodes.py").write_text(PLUGIN)
    tree = tmp_path / "tree.xml"
    tree.write_text(
        '<root BTCPP_format="4">\n<BehaviorTree ID="Main">\n<Sequence>\n<Script code="go := true"/>\n'
        '<ReactiveSequence>\n<ScriptCondition code="go"/>\n<Stubborn/>\n<Script code="go := false"/>\n'
        "</ReactiveSequence>\n</Sequence>\n</BehaviorTree>\n</root>\n"
    )
    assert main(["tree", "run", str(tree), "--dry", "--leaves", str(tmp_path / "nodes.py")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert "tree.xml:7: Stubborn 'Stubborn::" in err and "raised RuntimeError at " in err, err
    assert "nodes.py:21: cannot stop" in err, err
