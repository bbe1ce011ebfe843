"""Ports with BehaviorTree.CPP 4.10's rules (issue 38, finding 2 and 3), each written the way a porter of a Nav2 node
writes it. On main as it was:

- an output-only port of a type with no text form was refused at import ("type must be one of str, int, ...");
- a port declared with no default was required at load ("Plan needs the port 'start'"); ``default=None`` was the
  undocumented way round, written ``default="None"`` by ``tree models``;
- reading an entry with no value stopped the run (exit 2), where BT.CPP's ``getInput`` returns the error to the node;
- ``ports.has()`` said True for an optional port never set;
- a default its own type rejects was a traceback (exit 1) from ``tree validate`` and ``tree run``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from pathlib import Path

import pytest

from bt_grasp.cli.main import main
from bt_grasp.clock import ManualClock
from bt_grasp.errors import TreeFileError
from bt_grasp.nodes import DeclarationError, Leaf, Status, action, condition, input_port, output_port
from bt_grasp.tree import builtin_registry, load_tree_from_string
from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.formats.models import tree_nodes_model


@dataclass(frozen=True)
class NavPath:
    """A planned path: no text form (as ``nav_msgs::msg::Path``, which BT.CPP never parses from a tree file)."""

    goal: str
    points: int


@dataclass(frozen=True)
class PoseXY:
    """A pose written ``x;y`` in a tree file."""

    x: float
    y: float

    @classmethod
    def from_port_text(cls, text: str) -> PoseXY:
        x, sep, y = text.partition(";")
        if not sep:
            raise ValueError(f"'{text}' is not x;y")
        return cls(float(x), float(y))


@functools.cache
def _nodes() -> tuple[type[Leaf], type[Leaf]]:
    """The two nodes, declared when a test first asks (so each test fails on its own where a declaration does)."""

    @action(ports=[input_port("goal", str), input_port("start", PoseXY, description="where to plan from (optional)"),
                   output_port("path", NavPath)])
    class ComputePath(Leaf):
        """Nav2's ComputePathToPose, shaped: ``goal`` must be set, ``start`` is optional."""

        def update(self) -> Status:
            goal = self.ports.get("goal", str)
            if goal is None:  # BT.CPP: getInput returned an error; the node decides
                self.feedback_message = "no goal yet"
                return Status.FAILURE
            start = self.ports.get("start", PoseXY)
            self.blackboard.set("planned_from", "start" if start is not None else "robot")
            self.blackboard.set("start_given", self.ports.has("start"))
            self.ports.set("path", NavPath(goal, 3))
            return Status.SUCCESS

    @condition(ports=[input_port("path", NavPath)])
    class PathValid(Leaf):
        """SUCCESS for a path with points."""

        def update(self) -> Status:
            path = self.ports.require("path", NavPath)  # the strict form: no path is an error
            return Status.SUCCESS if path.points > 0 else Status.FAILURE

    return ComputePath, PathValid


def _tree(body: str) -> str:
    return f'<root BTCPP_format="4"><BehaviorTree ID="Main">{body}</BehaviorTree></root>'


def _load(body: str) -> tuple[object, ManualClock]:
    registry = builtin_registry()
    for node in _nodes():
        registry.register(node)
    clock = ManualClock()
    return load_tree_from_string(_tree(body), registry, clock=clock), clock


def test_an_output_only_custom_type_needs_no_text_form() -> None:
    tree, _ = _load('<Sequence><ComputePath goal="dock" path="{path}"/><PathValid path="{path}"/></Sequence>')
    # tick 1: ComputePath writes a NavPath, PathValid reads it from the blackboard: SUCCESS
    assert tree.tick().value == "SUCCESS"  # type: ignore[attr-defined]
    assert tree.blackboard_values()["path"] == NavPath("dock", 3)  # type: ignore[attr-defined]


def test_a_literal_of_a_type_with_no_text_form_is_a_load_error() -> None:
    with pytest.raises(TreeFileError, match=r"<string>:1: PathValid: port 'path': a NavPath cannot be written in a "
                                            r"tree file .*give a blackboard entry such as \{path\}"):
        _load('<PathValid path="a;b"/>')


def test_a_port_with_no_default_is_optional_as_in_btcpp() -> None:
    # start is not given: the tree loads; the node sees None and plans from the robot; has() says False
    tree, _ = _load('<ComputePath goal="dock" path="{path}"/>')
    assert tree.tick().value == "SUCCESS"  # type: ignore[attr-defined]
    values = tree.blackboard_values()  # type: ignore[attr-defined]
    assert (values["planned_from"], values["start_given"]) == ("robot", False)
    # given: a literal converted at load, has() True
    tree, _ = _load('<ComputePath goal="dock" start="1;2" path="{path}"/>')
    assert tree.tick().value == "SUCCESS"  # type: ignore[attr-defined]
    values = tree.blackboard_values()  # type: ignore[attr-defined]
    assert (values["planned_from"], values["start_given"]) == ("start", True)


def test_has_means_set_for_a_port_naming_an_entry() -> None:
    tree, _ = _load('<ComputePath goal="dock" start="{start}" path="{path}"/>')
    # tick 1: the entry {start} was never written: has() False, get() None
    assert tree.tick().value == "SUCCESS"  # type: ignore[attr-defined]
    assert tree.blackboard_values()["start_given"] is False  # type: ignore[attr-defined]
    tree.root_blackboard.set("start", PoseXY(1.0, 2.0))  # type: ignore[attr-defined]
    # tick 2: written since: has() True
    assert tree.tick().value == "SUCCESS"  # type: ignore[attr-defined]
    assert tree.blackboard_values()["start_given"] is True  # type: ignore[attr-defined]


def test_reading_an_entry_with_no_value_returns_to_the_node() -> None:
    tree, _ = _load('<ComputePath goal="{goal}" path="{path}"/>')
    # tick 1: {goal} has no value: get() is None, the node fails (BT.CPP's getInput error), the run goes on
    assert tree.tick().value == "FAILURE"  # type: ignore[attr-defined]
    assert tree.find("ComputePath").feedback_message == "no goal yet"  # type: ignore[attr-defined]
    tree.root_blackboard.set("goal", "dock")  # type: ignore[attr-defined]
    # tick 2: the goal is set (Nav2's navigator sets it before ticking): SUCCESS
    assert tree.tick().value == "SUCCESS"  # type: ignore[attr-defined]


def test_the_strict_form_is_an_explicit_choice_naming_the_line() -> None:
    tree, _ = _load('<Sequence>\n<PathValid path="{path}"/>\n</Sequence>')
    with pytest.raises(TreeRuntimeError, match=r"<string>:2: PathValid 'PathValid::2': port 'path' reads blackboard "
                                               r"entry 'path', which has no value yet"):
        tree.tick()  # type: ignore[attr-defined]


def test_default_none_is_refused_with_the_rule_and_models_write_no_default() -> None:
    with pytest.raises(DeclarationError, match="default=None: leave the default out"):
        input_port("start", PoseXY, None)
    model = tree_nodes_model([_nodes()[0].bt_spec])  # type: ignore[attr-defined]
    assert '<input_port name="start" type="PoseXY">where to plan from (optional)</input_port>' in model
    assert 'default="None"' not in model


BAD_DEFAULT = '''from dataclasses import dataclass

from bt_grasp.nodes import Leaf, Status, action, input_port


@dataclass
class Pose:
    x: float

    @classmethod
    def from_port_text(cls, text: str) -> "Pose":
        return cls(float(text))


@action(ports=[input_port("start", Pose, "")])
class Plan(Leaf):
    def update(self) -> Status:
        return Status.SUCCESS


def register(registry):
    registry.register(Plan)
'''


@pytest.mark.parametrize("command", [["tree", "validate"], ["tree", "run", "--dry"], ["tree", "models"]])
def test_a_default_its_type_rejects_is_one_line_with_file_and_line(
    command: list[str], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    plugin = tmp_path / "plan.py"
    plugin.write_text(BAD_DEFAULT)
    tree = tmp_path / "t.xml"
    tree.write_text(_tree("<Plan/>"))
    argv = [*command, "--leaves", str(plugin)] + ([str(tree)] if command[1] != "models" else [])
    assert main(argv) == 2  # not exit 1 with a traceback
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert err.strip() == (f"bt-grasp: error: {plugin}:15: bad declaration: port 'start': the default '' is not a "
                           "Pose (could not convert string to float: '')")
