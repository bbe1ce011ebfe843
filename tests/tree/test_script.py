"""The script language: precedence, assignment, strings, enums, errors."""

from __future__ import annotations

from typing import Any

import pytest

from bt_grasp.errors import TreeFileError
from bt_grasp.tree import Blackboard, builtin_registry, load_tree_from_string
from bt_grasp.tree.exceptions import ScriptSyntaxError, TreeRuntimeError
from bt_grasp.tree.scripting import parse_script


def run(code: str, bb: Blackboard | None = None, enums: dict[str, int] | None = None) -> Any:
    return parse_script(code).run(bb or Blackboard(), enums or {})


@pytest.mark.parametrize(
    ("code", "value"),
    [
        ("1 + 2 * 3", 7),
        ("(1 + 2) * 3", 9),
        ("10 - 4 - 3", 3),
        ("7 / 2", 3.5),
        ("-2 * 3", -6),
        ("2 * -3", -6),
        ("1 < 2 && 3 > 2", True),
        ("1 > 2 || 2 > 1", True),
        ("!false", True),
        ("!(1 == 1)", False),
        ("1 < 2 < 3", True),
        ("3 > 2 > 2", False),
        ("1 + 1 == 2", True),
        ("0.1 + 0.2 == 0.3", True),  # BT.CPP compares numbers with a float epsilon
        ("'a' .. 'b' .. 1", "ab1"),
        ("'ab' + 'cd'", "abcd"),
        ("'abc' == 'abc'", True),
        ("'2' == 2", True),
        ("true ? 'yes' : 'no'", "yes"),
        ("1 > 2 ? 1 : 2 + 3", 5),
        ("0x10 + 1", 17),
        ("1e3", 1000.0),
        ("6 & 3", 2),
        ("6 | 1", 7),
    ],
)
def test_expressions(code: str, value: Any) -> None:
    assert run(code) == value


def test_assignment_operators() -> None:
    bb = Blackboard()
    # an integer entry stays an integer through compound assignments (BT.CPP copies the real result back)
    assert run("a := 5; a += 2; a -= 1; a *= 3; a", bb) == 18
    assert run("a /= 3", bb) == 6 and isinstance(bb.get("a"), int)
    with pytest.raises(TreeRuntimeError, match="Invalid floating point to integer conversion"):
        run("a /= 4", bb)
    with pytest.raises(TreeRuntimeError, match="can't be converted"):
        run("a := 4.5", bb)  # an entry keeps the type of its first value
    run("r := 1; r = '2.5'; s := 'x'; s += 'y'", bb)  # a numeric string makes a number entry real
    assert bb.items() == {"a": 6, "r": 2.5, "s": "xy"}


def test_assign_existing_requires_the_entry() -> None:
    with pytest.raises(TreeRuntimeError, match=r"use the operator \[:=\] instead of \[=\]"):
        run("missing = 1")


def test_unknown_variable_is_a_runtime_error() -> None:
    with pytest.raises(TreeRuntimeError, match="Variable not found: nope"):
        run("nope + 1")


def test_number_entry_keeps_its_type() -> None:
    bb = Blackboard()
    run("n := 3; n = '4'", bb)
    assert bb.get("n") == 4


def test_enums_and_root_blackboard() -> None:
    root = Blackboard()
    child = Blackboard(root)
    run("@battery := 80", child)
    assert root.get("battery") == 80
    bb = Blackboard()
    bb.set("color", 2)
    assert run("color == BLUE", bb, {"RED": 1, "BLUE": 2}) == 1.0


def test_logical_operators_evaluate_both_sides_like_btcpp() -> None:
    bb = Blackboard()
    run("x := 0; ok := false && (x := 1) == 1", bb)
    assert bb.get("x") == 1 and bb.get("ok") == 0.0


@pytest.mark.parametrize(
    "code", ["a :=", "1 +* 2", "(1 + 2", "'open", "true := 1", "a ? b", '"double quoted"', "1.x", "a := 1 ? 2"]
)
def test_syntax_errors(code: str) -> None:
    with pytest.raises(ScriptSyntaxError):
        parse_script(code)


def test_script_syntax_error_is_a_load_error_with_the_line() -> None:
    xml = (
        '<root BTCPP_format="4">\n<BehaviorTree ID="M">\n<Sequence>\n'
        '<Script code="x := := 1"/>\n</Sequence>\n</BehaviorTree>\n</root>'
    )
    with pytest.raises(TreeFileError) as info:
        load_tree_from_string(xml, builtin_registry(), source="t.xml")
    assert str(info.value).startswith("t.xml:4: Script: script 'x := := 1'")


def test_condition_script_error_is_a_load_error() -> None:
    xml = '<root BTCPP_format="4"><BehaviorTree ID="M">\n<AlwaysSuccess _skipIf="a =="/></BehaviorTree></root>'
    with pytest.raises(TreeFileError, match=r"t.xml:2: _skipIf: script"):
        load_tree_from_string(xml, builtin_registry(), source="t.xml")


def test_a_tick_error_names_file_line_node_and_script() -> None:
    xml = (
        '<root BTCPP_format="4"><BehaviorTree ID="M">\n<Sequence>\n'
        '<Script code="n := 5; n /= 2"/>\n</Sequence></BehaviorTree></root>'
    )
    tree = load_tree_from_string(xml, builtin_registry(), source="t.xml")
    with pytest.raises(TreeRuntimeError) as info:
        tree.tick()
    assert str(info.value) == (
        "t.xml:3: Script 'Script::2': Error in script [n := 5; n /= 2]: Invalid floating point to integer conversion"
    )
