"""``<TreeNodesModel>``: the description of node types Groot2 reads to offer them in its palette, with their
ports (``bt-grasp tree models``)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Iterable

from bt_grasp.tree.registry import NodeSpec, PortDirection, model_type_name
from bt_grasp.tree.values import to_text

_PORT_TAG = {
    PortDirection.INPUT: "input_port",
    PortDirection.OUTPUT: "output_port",
    PortDirection.INOUT: "inout_port",
}


def tree_nodes_model(specs: Iterable[NodeSpec]) -> str:
    """A ``<root BTCPP_format="4">`` document holding one ``<TreeNodesModel>`` entry per spec."""
    root = ET.Element("root", {"BTCPP_format": "4"})
    models = ET.SubElement(root, "TreeNodesModel")
    for spec in specs:
        element = ET.SubElement(models, spec.kind.value, {"ID": spec.name})
        for port in spec.ports:
            attributes = {"name": port.name}
            type_name = model_type_name(port.type)  # int, double, bool, std::string, or the class's name
            if type_name is not None:
                attributes["type"] = type_name
            if port.has_default:
                attributes["default"] = (
                    to_text(port.default)
                    if not isinstance(port.default, bool)
                    else ("true" if port.default else "false")
                )
            port_element = ET.SubElement(element, _PORT_TAG[port.direction], attributes)
            if port.description:
                port_element.text = port.description
        if spec.description:
            ET.SubElement(element, "description").text = spec.description
    ET.indent(root, space="  ")
    return ET.tostring(root, encoding="unicode") + "\n"
