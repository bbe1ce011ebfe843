"""docs/own-leaves.md's complete example is run as written: its plugin file and tree are taken from the page,
validated, listed for Groot2 and dry-run through the CLI, and its robot leaf ticked against a stand-in robot."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from numpy.typing import NDArray

from bt_grasp.behaviours.cell import make_cell
from bt_grasp.cli.main import main
from bt_grasp.clock import ManualClock
from bt_grasp.scene.format import Scene
from bt_grasp.tree import builtin_registry, load_tree_from_string
from bt_grasp.tree.plugins import load_file

DOC = Path(__file__).resolve().parents[2] / "docs" / "own-leaves.md"


def _blocks(language: str) -> list[str]:
    example = DOC.read_text().split("## A complete example", 1)[1].split("\n## ", 1)[0]  # that section alone
    return re.findall(rf"```{language}\n(.*?)```", example, flags=re.S)


@pytest.fixture
def example(tmp_path: Path) -> tuple[Path, Path]:
    (python,), (xml,) = _blocks("python"), _blocks("xml")
    plugin, tree = tmp_path / "my_leaves.py", tmp_path / "settle.xml"
    plugin.write_text(python)
    tree.write_text(xml)
    return plugin, tree


def test_the_pages_commands_work(example: tuple[Path, Path], tmp_path: Path,
                                 capsys: pytest.CaptureFixture[str]) -> None:
    plugin, tree = example
    assert main(["tree", "validate", "--leaves", str(plugin), str(tree)]) == 0
    models = tmp_path / "my_nodes.xml"
    assert main(["tree", "models", "--leaves", str(plugin), "--only-plugins", "--out", str(models)]) == 0
    assert re.findall(r' ID="(\w+)"', models.read_text()) == ["RateLimit", "WaitSettled"]
    capsys.readouterr()
    # one tick: MoveHome's stand-in succeeds, WaitSettled's (the user's robot leaf) fails with the user's
    # NOT_SETTLED, FailureIs recovers, RateLimit (the user's decorator, real) starts OpenGripper's stand-in
    assert main(["tree", "run", "--dry", "--json", "--leaves", str(plugin), str(tree),
                 "--outcome", "WaitSettled=failure:NOT_SETTLED"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert (out["status"], out["ticks"]) == ("SUCCESS", 1)
    tick_1 = [(move["path"].rsplit("/", 1)[-1], move["to"]) for move in out["transitions"] if move["tick"] == 1]
    assert ("WaitSettled::4", "FAILURE") in tick_1 and ("FailureIs::5", "SUCCESS") in tick_1  # NOT_SETTLED matched
    assert "failure_reason" not in out["blackboard"]  # the tree succeeded: the recovered failure is cleared
    assert main(["tree", "run", "--dry", "--leaves", str(plugin), str(tree)]) == 0  # no set-up: all succeed
    assert capsys.readouterr().out.startswith("SUCCESS after 1 ticks")


class MovingArm:
    """Joint speeds the test sets; the rest of the Robot protocol is not used by WaitSettled."""

    def __init__(self) -> None:
        self.speed = 0.5

    def joint_velocities(self) -> NDArray[np.float64]:
        return np.array([0.0, self.speed, 0.0, 0.0, 0.0, 0.0])


class NoCamera:
    def capture(self) -> None:
        return None


def test_the_pages_robot_leaf_tick_by_tick(example: tuple[Path, Path]) -> None:
    plugin, _ = example
    registry = builtin_registry()
    load_file(plugin).register(registry)
    clock, arm = ManualClock(), MovingArm()
    tree = load_tree_from_string(
        '<root BTCPP_format="4"><BehaviorTree ID="M"><WaitSettled timeout_s="0.02"/></BehaviorTree></root>',
        registry, clock=clock)
    cell = make_cell(arm, NoCamera(), clock, Scene(), seed=0)  # type: ignore[arg-type]
    for node in tree.nodes():
        node.setup(cell=cell)
    statuses = []
    for _ in range(3):  # t = 0, 10, 20 ms: moving at 0.5 rad/s; the deadline is t=20 ms
        statuses.append(tree.tick().value)
        clock.advance_s(0.010)
    assert statuses == ["RUNNING", "RUNNING", "FAILURE"]
    assert tree.root_blackboard.get("failure_reason") == "NOT_SETTLED"
    arm.speed = 0.001  # still: the next attempt succeeds at once
    assert tree.tick().value == "SUCCESS"
