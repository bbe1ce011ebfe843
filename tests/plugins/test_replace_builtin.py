"""A plugin that brings a node of a name bt_grasp already uses (another BT.CPP project's `OpenGripper`):
registering it over the shipped one is refused with the way out in the sentence; `registry.unregister(name)` first
(BT.CPP's `unregisterBuilder`) replaces it, and every tree command then uses the user's node."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bt_grasp.cli.main import main
from bt_grasp.tree.builtins import builtin_registry

LEAF = '''
from bt_grasp.nodes import Leaf, Status, action, input_port


@action(name="OpenGripper", ports=[input_port("width", float, 0.08, "opening in metres")])
class TheirOpenGripper(Leaf):
    """Their project's OpenGripper: succeeds on the second tick."""

    def initialise(self) -> None:
        self.ticks = 0

    def update(self) -> Status:
        self.ticks += 1
        self.blackboard.set("opened_to", self.ports.get("width"))
        return Status.SUCCESS if self.ticks >= 2 else Status.RUNNING


def register(registry):
{body}
'''

TREE = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence>
      <OpenGripper width="0.05"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


def _plugin(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "their_leaves.py"
    path.write_text(LEAF.format(body=body))
    return path


@pytest.fixture
def tree_file(tmp_path: Path) -> Path:
    path = tmp_path / "theirs.xml"
    path.write_text(TREE)
    return path


def test_registering_over_a_shipped_node_names_the_way_out(tree_file: Path, tmp_path: Path,
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    plugin = _plugin(tmp_path, "    registry.register(TheirOpenGripper)")
    assert main(["tree", "validate", "--leaves", str(plugin), str(tree_file)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"bt-grasp: error: {plugin}:19: bad declaration: a node named 'OpenGripper' is already "
                   "registered by bt_grasp (to replace it, call registry.unregister('OpenGripper') first)")


def test_unregister_then_register_replaces_it_in_every_tree_command(tree_file: Path, tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture[str]) -> None:
    plugin = _plugin(tmp_path, "    assert registry.unregister('OpenGripper')\n"
                               "    registry.register(TheirOpenGripper)")
    # the shipped OpenGripper has no 'width' port: validation with the user's node accepts it
    assert main(["tree", "validate", str(tree_file)]) == 2
    assert "width" in capsys.readouterr().err
    assert main(["tree", "validate", "--leaves", str(plugin), str(tree_file)]) == 0
    capsys.readouterr()
    # tick 1: OpenGripper (theirs) RUNNING, Sequence RUNNING; tick 2: SUCCESS, Sequence SUCCESS. The shipped
    # OpenGripper needs the robot, so a dry run would have replaced it by a one-tick stand-in that sets nothing
    assert main(["tree", "run", "--dry", "--json", "--leaves", str(plugin), str(tree_file)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["status"] == "SUCCESS" and out["ticks"] == 2
    assert out["blackboard"]["opened_to"] == 0.05
    # tree models: the user's ports, not the shipped ones
    assert main(["tree", "models", "--leaves", str(plugin)]) == 0
    models = capsys.readouterr().out
    line = next(x for x in models.splitlines() if 'ID="OpenGripper"' in x)
    block = models[models.index(line):models.index("</Action>", models.index(line))]
    assert 'name="width"' in block


def test_unregister_says_whether_there_was_such_a_node() -> None:
    registry = builtin_registry()
    assert "Sequence" in registry
    assert registry.unregister("Sequence") is True
    assert "Sequence" not in registry
    assert registry.unregister("Sequence") is False
    assert registry.unregister("NoSuchNode") is False
    assert "Sequence" in builtin_registry()  # a fresh registry each time: nothing shared was changed
