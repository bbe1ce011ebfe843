"""What recorders and viewers read from a built tree.

``node_records(root)`` is a flat, per-tick view (status); ``tree_structure(root)`` the nested, static one;
``to_btcpp_xml(root)`` the expanded tree as BT.CPP exports it for Groot2 (``_uid``, ``_fullpath``).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

from bt_grasp.tree.node import BtNode
from bt_grasp.tree.records import NodeSnapshot, TreeNode


def _walk(root: BtNode) -> list[BtNode]:
    return [n for n in root.iterate() if isinstance(n, BtNode)]


def bt_status_name(node: BtNode) -> str:
    """BT.CPP's status name: IDLE, RUNNING, SUCCESS, FAILURE, or SKIPPED (see ``BtNode``)."""
    if node.bt_status_extra == "SKIPPED":
        return "SKIPPED"
    return node.bt_state.value


def node_records(root: BtNode) -> list[NodeSnapshot]:
    """One dict per node, in uid order: uid, type, name, path, kind, status (py_trees name),
    bt_status (BT.CPP name, including SKIPPED), feedback_message, failure_reason."""
    records: list[NodeSnapshot] = []
    for node in sorted(_walk(root), key=lambda n: n.bt_uid):
        records.append(
            {
                "uid": node.bt_uid,
                "type": node.bt_type,
                "name": node.name,
                "path": node.bt_path,
                "kind": node.bt_kind.value,
                "status": node.status.name,
                "bt_status": bt_status_name(node),
                "feedback_message": node.feedback_message,
                "failure_reason": getattr(node, "failure_reason", None),
            }
        )
    return records


def tree_structure(root: BtNode) -> TreeNode:
    """The nested structure: uid, type, name, path, kind, attributes (as written), children."""
    entry: TreeNode = {
        "uid": root.bt_uid,
        "type": root.bt_type,
        "name": root.name,
        "path": root.bt_path,
        "kind": root.bt_kind.value,
        "attributes": dict(root.bt_attributes),
        "children": [tree_structure(c) for c in root.bt_children()],
    }
    subtree_id = getattr(root, "subtree_id", None)
    if subtree_id:
        entry["subtree_id"] = subtree_id
    return entry


def to_btcpp_xml(root: BtNode, main_tree: str) -> str:
    """The expanded tree in BT.CPP's export form: one ``<BehaviorTree>`` per subtree instance."""
    xml_root = ET.Element("root", {"BTCPP_format": "4", "main_tree_to_execute": main_tree})
    trees: list[tuple[str, str, BtNode]] = [(main_tree, "", root)]
    index = 0
    while index < len(trees):
        tree_id, fullpath, top = trees[index]
        index += 1
        tree_element = ET.SubElement(xml_root, "BehaviorTree", {"ID": tree_id, "_fullpath": fullpath})

        def add(node: BtNode, parent: ET.Element) -> None:
            subtree_id = getattr(node, "subtree_id", None)
            if subtree_id:
                attributes = {"ID": subtree_id, "_fullpath": getattr(node, "subtree_path", node.bt_path)}
            else:
                attributes = {"name": node.name}
            attributes["_uid"] = str(node.bt_uid)
            for key, value in node.bt_attributes.items():
                if key not in ("name", "ID"):
                    attributes.setdefault(key, value)
            element = ET.SubElement(parent, "SubTree" if subtree_id else node.bt_type, attributes)
            if subtree_id:
                trees.append((subtree_id, attributes["_fullpath"], node.bt_children()[0]))
                return
            for child in node.bt_children():
                add(child, element)

        add(top, tree_element)
    ET.indent(xml_root, space="  ")
    return ET.tostring(xml_root, encoding="unicode") + "\n"
