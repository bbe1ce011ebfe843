"""Convert tree files between BT.CPP v4 XML and the YAML twin format.

Both directions go through :class:`Document`, so a converted file loads to the same tree. Includes stay
references (their paths are copied as written); comments are not carried over.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from bt_grasp.errors import InputError
from bt_grasp.tree.formats.document import Document, NodeDecl
from bt_grasp.tree.formats.yaml_format import write_yaml

_PORT_TAGS = {"input": "input_port", "output": "output_port", "inout": "inout_port"}


def _node_element(decl: NodeDecl) -> ET.Element:
    element = ET.Element(decl.type_id)
    if decl.subtree_id is not None:
        element.set("ID", decl.subtree_id)
    for key, value in decl.attributes:
        element.set(key, value)
    for child in decl.children:
        element.append(_node_element(child))
    return element


def write_xml(document: Document) -> str:
    """``document`` as BT.CPP v4 XML (compact form)."""
    root = ET.Element("root", {"BTCPP_format": "4"})
    if document.main_tree is not None:
        root.set("main_tree_to_execute", document.main_tree)
    for inc in document.includes:
        ET.SubElement(root, "include", {"path": inc.path})
    for tree_id, tree in document.trees.items():
        tree_element = ET.SubElement(root, "BehaviorTree", {"ID": tree_id})
        tree_element.append(_node_element(tree.root))
    if document.models:
        models = ET.SubElement(root, "TreeNodesModel")
        for model in document.models:
            model_element = ET.SubElement(models, model.kind, {"ID": model.node_id})
            for port in model.ports:
                attributes = {"name": port.name}
                if port.type_name:
                    attributes["type"] = port.type_name
                if port.default is not None:
                    attributes["default"] = port.default
                port_element = ET.SubElement(model_element, _PORT_TAGS.get(port.direction, "input_port"), attributes)
                if port.description:
                    port_element.text = port.description
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="unicode") + "\n"


def format_of(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix == ".xml":
        return "xml"
    if suffix in (".yaml", ".yml"):
        return "yaml"
    raise InputError(path, f"unknown tree file extension '{suffix}'; use .xml, .yaml or .yml")


def write_document(document: Document, fmt: str) -> str:
    return write_xml(document) if fmt == "xml" else write_yaml(document)


def convert_file(source: Path, target: Path) -> Document:
    """Read ``source`` (one file, includes not followed) and write it to ``target`` in the other format."""
    from bt_grasp.tree.loader import read_single

    document = read_single(source)
    target.write_text(write_document(document, format_of(target)), encoding="utf-8")
    return document
