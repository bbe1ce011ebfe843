"""The "did you mean" of an unknown attribute points the way the tree meant (issue 43, finding 5).

On main, docs/tree-format.md's first example, ``<Action ID="Perceive" detections="{detections}"/>``, was told
"did you mean 'detector'?": an input that chooses the detector, not where detections go. A misspelling still
names the port it misspells; another word names the port whose description uses it; the listing says which
ports are inputs and which outputs."""

from __future__ import annotations

import pytest

from bt_grasp.behaviours import robot_registry
from bt_grasp.errors import TreeFileError
from bt_grasp.tree import load_tree_from_string


def _error(node: str) -> str:
    text = f'<root BTCPP_format="4"><BehaviorTree ID="M"><Sequence>{node}</Sequence></BehaviorTree></root>'
    with pytest.raises(TreeFileError) as err:
        load_tree_from_string(text, robot_registry())
    return str(err.value)


def test_the_tree_format_example_is_pointed_at_an_output() -> None:
    text = _error('<Action ID="Perceive" detections="{detections}"/>')
    assert "(inputs: color, detector, model, imgsz; outputs: target, objects)" in text, text
    assert text.endswith("; did you mean 'target' (output: the chosen detection)?"), text
    assert "'detector'" not in text.split("did you mean")[1]


@pytest.mark.parametrize(("node", "meant"), [
    ('<Perceive colr="red"/>', "'color' (input:"),
    ('<Perceive objcts="{o}"/>', "'objects' (output:"),
    ('<PlanGrasp targt="{t}"/>', "'target' (input:"),
    ('<Grasp froce="20"/>', "'force' (input:"),
    ('<AlwaysSuccess _skipif="true"/>', "'_skipIf'?"),
    ('<Sleep duration="3"/>', "'msec' (input: duration"),
])
def test_a_misspelling_or_a_described_word_names_its_port(node: str, meant: str) -> None:
    assert f"did you mean {meant}" in _error(node)


def test_no_hint_for_a_word_nothing_uses() -> None:
    text = _error('<Grasp banana="1"/>')
    assert "did you mean" not in text and "(inputs: force, grasp; outputs: width)" in text, text
