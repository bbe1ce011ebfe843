"""Blackboards, SubTree remapping, uids and paths (BT.CPP's blackboard.cpp and xml_parsing.cpp)."""

from __future__ import annotations

from bt_grasp.tree import Blackboard
from bt_grasp.tree.introspect import node_records, tree_structure

from .harness import Harness, S

TWO_TREES = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence>
      <Script code="target := 'cube'; count := 1"/>
      <SubTree ID="Pick" name="pick" object="{target}" mode="fast" result="{out}"/>
      <SubTree ID="Pick" object="{target}" mode="slow" result="{out2}"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Pick">
    <Sequence>
      <Script code="result := object .. '-' .. mode; private := 1"/>
      <Stub name="Grip" out="{grip}"/>
    </Sequence>
  </BehaviorTree>
</root>"""


def test_subtree_remapping_literals_and_isolation() -> None:
    h = Harness(TWO_TREES)
    assert h.tick() == S
    # remapped ports write through to the parent's entries; private ones stay inside
    assert h.bb["out"] == "cube-fast" and h.bb["out2"] == "cube-slow"
    assert "private" not in h.bb and "grip" not in h.bb and "mode" not in h.bb


def test_uids_are_depth_first_and_paths_follow_btcpp() -> None:
    h = Harness(TWO_TREES)
    records = node_records(h.tree.root)
    assert [(r["uid"], r["type"], r["path"]) for r in records] == [
        (1, "Sequence", "Sequence::1"),
        (2, "Script", "Script::2"),
        (3, "SubTree", "pick"),
        (4, "Sequence", "pick/Sequence::4"),
        (5, "Script", "pick/Script::5"),
        (6, "Stub", "pick/Grip"),
        (7, "SubTree", "Pick::7"),
        (8, "Sequence", "Pick::7/Sequence::8"),
        (9, "Script", "Pick::7/Script::9"),
        (10, "Stub", "Pick::7/Grip"),
    ]
    structure = tree_structure(h.tree.root)
    pick = structure["children"][1]
    assert pick["kind"] == "SubTree" and pick["subtree_id"] == "Pick"
    assert pick["attributes"] == {"name": "pick", "object": "{target}", "mode": "fast", "result": "{out}"}
    assert 'SubTree ID="Pick" _fullpath="pick" _uid="3"' in h.tree.btcpp_xml


def test_autoremap_and_same_name_shortcut() -> None:
    xml = """<root BTCPP_format="4" main_tree_to_execute="Main">
      <BehaviorTree ID="Main"><Sequence>
        <Script code="a := 1; b := 2"/>
        <SubTree ID="Auto" _autoremap="true"/>
        <SubTree ID="Same" b="{=}"/>
      </Sequence></BehaviorTree>
      <BehaviorTree ID="Auto"><Script code="a += 10; c := 3; _hidden := 4"/></BehaviorTree>
      <BehaviorTree ID="Same"><Script code="b *= 5; @rooted := true"/></BehaviorTree>
    </root>"""
    h = Harness(xml)
    assert h.tick() == S
    assert h.bb == {"a": 11, "b": 10, "c": 3, "rooted": True}


def test_output_port_shortcut_and_blackboard_typing() -> None:
    h = Harness('<Sequence><Stub name="A"/><Stub name="B" out="{counter}"/></Sequence>')
    assert h.tick() == S
    # Stub's port "out" defaults to "{=}": A writes entry "out"; B writes "counter"
    assert h.bb == {"out": 1, "counter": 1}


def test_blackboard_remapping_primitives() -> None:
    root = Blackboard()
    child = Blackboard(root)
    child.add_remapping("inner", "outer")
    child.set("inner", 5)
    assert root.get("outer") == 5 and child.has("inner") and not root.has("inner")
    child.set_local("lit", "x")
    assert child.get("lit") == "x" and not root.exists("lit")
    auto = Blackboard(root, autoremap=True)
    auto.set("shared", 1)
    auto.set("_mine", 2)
    assert root.get("shared") == 1 and not root.exists("_mine")
