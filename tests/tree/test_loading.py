"""Registry, includes, TreeNodesModel, substitution, YAML round trips."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from bt_grasp.errors import InputError, TreeFileError
from bt_grasp.nodes import Leaf, NodeContext, NodeRegistry, Status, action, input_port
from bt_grasp.tree import builtin_registry, load_tree, load_tree_from_string
from bt_grasp.tree.formats.convert import convert_file, write_xml
from bt_grasp.tree.formats.yaml_format import read_yaml, write_yaml
from bt_grasp.tree.kinds import NodeKind
from bt_grasp.tree.loader import read_document

from .harness import F, Harness, R, S


def test_registry_contract() -> None:
    registry = NodeRegistry()

    @action(ports=[input_port("target", str)], needs_robot=True)
    class Approach(Leaf):
        """Move the gripper above the target."""

        def update(self) -> Status:
            return Status.SUCCESS

    spec = registry.register(Approach)
    assert registry["Approach"] is spec
    assert spec.kind is NodeKind.ACTION and spec.needs_robot and spec.children == (0, 0)
    assert spec.description == "Move the gripper above the target." and spec.factory is Approach
    with pytest.raises(ValueError, match="already registered by bt_grasp"):
        registry.register(Approach)
    copy = registry.copy()
    assert copy.names() == ("Approach",) and copy is not registry
    full = builtin_registry()
    full.register(Approach)
    assert full.nearest("Aproach") == ["Approach"]
    assert "Approach" not in builtin_registry()  # no global state


def test_include_is_relative_to_the_including_file(tmp_path: Path) -> None:
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "grasp.yaml").write_text('trees:\n  Grasp:\n    Script: {code: "grasped := true"}\n')
    (tmp_path / "lib.xml").write_text(
        '<root BTCPP_format="4"><include path="sub/grasp.yaml"/>'
        '<BehaviorTree ID="Pick"><SubTree ID="Grasp" _autoremap="true"/></BehaviorTree></root>'
    )
    main = tmp_path / "main.xml"
    main.write_text(
        '<root BTCPP_format="4" main_tree_to_execute="Main"><include path="lib.xml"/>'
        '<BehaviorTree ID="Main"><SubTree ID="Pick" _autoremap="true"/></BehaviorTree></root>'
    )
    tree = load_tree(main, builtin_registry())
    assert tree.tick().value == S and tree.root_blackboard.items() == {"grasped": True}
    assert set(tree.sources) == {str(main), str(tmp_path / "lib.xml"), str(tmp_path / "sub" / "grasp.yaml")}


def test_tree_nodes_model_is_accepted_and_gives_subtree_defaults() -> None:
    xml = """<root BTCPP_format="4" main_tree_to_execute="Main">
      <BehaviorTree ID="Main"><SubTree ID="Wait"/></BehaviorTree>
      <BehaviorTree ID="Wait"><Sleep msec="{ms}"/></BehaviorTree>
      <TreeNodesModel>
        <Action ID="Sleep"><input_port name="msec" type="unsigned int">milliseconds</input_port></Action>
        <Action ID="SomethingGroot2Knows"/>
        <SubTree ID="Wait"><input_port name="ms" default="10"/></SubTree>
      </TreeNodesModel>
    </root>"""
    tree = load_tree_from_string(xml, builtin_registry())
    assert tree.tick().value == R
    tree.clock.advance_s(0.01)
    assert tree.tick().value == S


def test_subtree_model_makes_ports_mandatory() -> None:
    xml = """<root BTCPP_format="4" main_tree_to_execute="Main">
      <BehaviorTree ID="Main">
        <SubTree ID="Wait"/></BehaviorTree>
      <BehaviorTree ID="Wait"><Sleep msec="{ms}"/></BehaviorTree>
      <TreeNodesModel><SubTree ID="Wait"><input_port name="ms"/></SubTree></TreeNodesModel>
    </root>"""
    with pytest.raises(TreeFileError, match=r"<string>:3: SubTree Wait needs the port 'ms'"):
        load_tree_from_string(xml, builtin_registry())


def test_substitution_rules() -> None:
    xml = """<Sequence>
      <Stub name="Perceive"/>
      <Stub name="Approach"/>
      <Fallback><Stub name="Grasp"/><FailureIs reason="SLIPPED"/></Fallback>
    </Sequence>"""
    h = Harness(xml, substitutions={"Perceive": "AlwaysSuccess", "Approach": "Running:2", "Grasp": "Failure:SLIPPED"})
    # Approach (stand-in) runs 2 ticks then succeeds; Grasp fails with SLIPPED, FailureIs recovers
    assert [h.tick(), h.tick(), h.tick()] == [R, R, S]
    assert h.stubs == {}  # no Stub was built
    assert h.node("Approach").bt_type == "TestNode" and h.node("Perceive").bt_type == "AlwaysSuccess"
    assert h.node("Grasp").failure_reason == "SLIPPED"  # type: ignore[attr-defined]  # FailureIs matched it
    assert "failure_reason" not in h.bb  # the tree succeeded: cleared


@pytest.mark.parametrize("replacement", ["Sequence", "Teleport", "Running:x", "SetBlackboard"])
def test_bad_substitution_is_an_input_error(replacement: str) -> None:
    with pytest.raises(InputError, match="substitution"):
        Harness("<Stub name='A'/>", substitutions={"A": replacement})


def test_robot_leaves_are_reported() -> None:
    h = Harness('<Sequence><Arm name="Move"/><AlwaysSuccess/></Sequence>')
    assert [n.name for n in h.tree.robot_nodes()] == ["Move"]
    h2 = Harness('<Sequence><Arm name="Move"/></Sequence>', substitutions={"Arm": "AlwaysSuccess"})
    assert h2.tree.robot_nodes() == []


def test_explicit_and_compact_forms_are_the_same_tree() -> None:
    compact = Harness('<Sequence><Stub name="A"/><Check name="B"/></Sequence>')
    explicit = Harness('<Control ID="Sequence"><Action ID="Stub" name="A"/><Condition ID="Check" name="B"/></Control>')
    assert [n.bt_path for n in compact.nodes()] == [n.bt_path for n in explicit.nodes()]


def test_nothing_runs_when_loading_fails() -> None:
    registry = builtin_registry()
    built: list[str] = []

    @action()
    class Spy(Leaf):
        def __init__(self, ctx: NodeContext) -> None:
            super().__init__(ctx)
            built.append(ctx.name)

        def update(self) -> Status:
            raise AssertionError("must not tick")

    registry.register(Spy)
    with pytest.raises(TreeFileError):
        load_tree_from_string('<root BTCPP_format="4"><BehaviorTree><Sequence><Spy/><Nope/></Sequence>'
                              "</BehaviorTree></root>", registry)  # fmt: skip
    assert built == []


ROUND_TRIP = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence name="pick">
      <Script code="tries := 0; ok := false"/>
      <RetryUntilSuccessful num_attempts="3">
        <Sequence>
          <Script code="tries += 1"/>
          <Stub name="Grasp" _onSuccess="ok := true"/>
        </Sequence>
      </RetryUntilSuccessful>
      <Timeout msec="50"><Stub name="Lift"/></Timeout>
      <SubTree ID="Place" where="{tries}"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Place">
    <ReactiveSequence><Check name="Held" _skipIf="where &gt; 5"/><Sleep msec="20"/></ReactiveSequence>
  </BehaviorTree>
  <TreeNodesModel><Action ID="Sleep"><input_port name="msec" type="int"/></Action></TreeNodesModel>
</root>
"""


def _stream(path: Path) -> list[tuple[str, list[tuple[str, str]]]]:
    h = Harness(path.read_text()) if path.suffix == ".xml" else None
    if h is None:
        h = Harness.__new__(Harness)
        Harness.__init__(h, write_xml(read_yaml(path.read_bytes(), str(path))))
    h["Grasp"].returns(F, S)
    h["Lift"].returns(R, R, R, S)
    stream = []
    for _ in range(8):
        status = h.tick()
        stream.append((status, [(n.bt_path, n.bt_state.value) for n in h.nodes()]))
        h.clock.advance_s(0.02)
    return stream


def test_yaml_round_trip_preserves_structure_and_tick_stream(tmp_path: Path) -> None:
    xml_path = tmp_path / "pick.xml"
    xml_path.write_text(ROUND_TRIP)
    yaml_path = tmp_path / "pick.yaml"
    back_path = tmp_path / "back.xml"
    convert_file(xml_path, yaml_path)
    convert_file(yaml_path, back_path)
    original = read_document(xml_path.read_bytes(), str(xml_path))
    assert read_yaml(yaml_path.read_bytes(), str(yaml_path)).structure() == original.structure()
    assert read_document(back_path.read_bytes(), str(back_path)).structure() == original.structure()
    assert write_yaml(read_yaml(yaml_path.read_bytes(), "x")) == yaml_path.read_text()
    xml_stream = _stream(xml_path)
    assert xml_stream == _stream(yaml_path)
    # t=0..40ms: Lift RUNNING under Timeout(50ms); t=60ms: timeout -> FAILURE; then a fresh attempt
    assert [s for s, _ in xml_stream][:5] == [R, R, R, F, R]


def test_yaml_tree_loads_directly(tmp_path: Path) -> None:
    path = tmp_path / "t.yml"
    path.write_text(
        "main_tree_to_execute: Main\ntrees:\n  Main:\n    Sequence:\n      children:\n"
        '        - Script: {code: "n := 2"}\n        - Repeat:\n            num_cycles: 3\n'
        '            children: [{Script: {code: "n *= 2"}}]\n        - AlwaysSuccess\n'
    )
    tree = load_tree(path, builtin_registry())
    assert tree.tick().value == S and tree.root_blackboard.get("n") == 16


@pytest.mark.parametrize(
    ("model", "warning"),
    [
        ('<Condition ID="Sleep"/>', "<string>:4: TreeNodesModel: Sleep is registered as an Action, the model says"),
        ('<Action ID="Sleep"><input_port name="duration"/></Action>', "<string>:4: TreeNodesModel: Sleep has no port"),
        ('<Action ID="Sleep"><input_port name="msec" type="std::string"/></Action>',
         "<string>:4: TreeNodesModel: port 'msec' of Sleep has type int, the model says std::string"),
    ],
)
def test_a_model_that_disagrees_with_a_registered_node_is_a_warning(
    model: str, warning: str, caplog: pytest.LogCaptureFixture
) -> None:
    """BT.CPP ignores the models of registered nodes (tests/tree_conformance/corpus/ext_model_*.xml: it loads and
    runs such trees), so a stand-in that declares fewer ports than the other project's node still loads."""
    xml = f"""<root BTCPP_format="4">
      <BehaviorTree ID="Main"><Sleep msec="5"/></BehaviorTree>
      <TreeNodesModel>
        {model}
      </TreeNodesModel>
    </root>"""
    with caplog.at_level(logging.WARNING, logger="bt_grasp.tree"):
        tree = load_tree_from_string(xml, builtin_registry())
    assert tree.tick().value == R
    assert any(warning in record.getMessage() for record in caplog.records), caplog.text
