"""Read BehaviorTree.CPP v4 XML into a :class:`Document`, safely and with line numbers.

Parsing goes through defusedxml's expat parser with DTDs, entity declarations and external references
forbidden, so entity-expansion bombs, quadratic blow-ups and ``file:///etc/passwd`` entities are refused
(at the line of their ``<!DOCTYPE``) before anything is expanded. Each element records the line expat was
on when it started.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Iterator
from typing import Protocol

import defusedxml
from defusedxml.ElementTree import DefusedXMLParser, ParseError

from bt_grasp.errors import TreeFileError
from bt_grasp.tree.formats.document import (
    EXPLICIT_TAGS,
    Document,
    IncludeDecl,
    ModelDecl,
    ModelPort,
    NodeDecl,
    TreeDecl,
)

logger = logging.getLogger(__name__)

#: a model's port elements; ``bidirectional_port`` is Groot 1's name for ``inout_port`` (Nav2's nav2_tree_nodes.xml
#: still writes it; BT.CPP reads only SubTree models and so never minds)
_PORT_TAGS = {"input_port": "input", "output_port": "output", "inout_port": "inout", "bidirectional_port": "inout"}
_MODEL_TAGS = EXPLICIT_TAGS | {"SubTree"}


class Element(Protocol):
    """An XML element as defusedxml's parser builds it (ElementTree's interface; defusedxml builds them with its own
    copy of the pure-Python module, so ``xml.etree.ElementTree.Element`` is not their class)."""

    tag: str
    attrib: dict[str, str]
    text: str | None

    def __iter__(self) -> Iterator[Element]: ...


class _LineRecordingParser(DefusedXMLParser):  # type: ignore[misc]
    """defusedxml's parser, also storing ``sourceline`` on every element."""

    def _start(self, tag: str, attr_list: list[str]) -> Element:
        element: Element = super()._start(tag, attr_list)
        element.sourceline = self.parser.CurrentLineNumber  # type: ignore[attr-defined]  # read by _line
        return element


#: elements nested deeper than this are refused (a person's tree is a dozen deep; 5,000 was a RecursionError)
MAX_XML_DEPTH = 100


def parse_xml(data: bytes, source: str) -> Element:
    """The root element of ``data``; every problem is a :class:`TreeFileError` with its line."""
    parser = _LineRecordingParser(forbid_dtd=True, forbid_entities=True, forbid_external=True)
    try:
        parser.feed(data)
        root: Element = parser.close()
    except ParseError as exc:
        line = exc.position[0] if getattr(exc, "position", None) else None
        message = re.sub(r": line \d+, column \d+$", "", str(exc))
        raise TreeFileError(source, f"malformed XML: {message}", where=line) from None
    except defusedxml.DTDForbidden:
        line = parser.parser.CurrentLineNumber
        raise TreeFileError(
            source, "a <!DOCTYPE> is not allowed in a tree file (no DTDs, entities or external references)", line
        ) from None
    except (defusedxml.EntitiesForbidden, defusedxml.ExternalReferenceForbidden, defusedxml.NotSupportedError):
        line = parser.parser.CurrentLineNumber
        raise TreeFileError(source, "XML entities and external references are not allowed", line) from None
    stack = [(root, 1)]
    while stack:  # iterative: the nesting is checked before anything walks it recursively
        element, depth = stack.pop()
        if depth > MAX_XML_DEPTH:
            raise TreeFileError(source, f"elements are nested deeper than {MAX_XML_DEPTH} levels", _line(element))
        stack.extend((child, depth + 1) for child in element)
    return root


def _line(element: Element) -> int:
    return int(getattr(element, "sourceline", 0) or 0)


def _children(element: Element) -> list[Element]:
    return [c for c in element if isinstance(c.tag, str)]


def _node(element: Element, source: str) -> NodeDecl:
    tag = element.tag
    line = _line(element)
    attributes = [(k, v) for k, v in element.attrib.items() if k != "ID"]
    element_id = element.attrib.get("ID")
    children = tuple(_node(c, source) for c in _children(element))
    if tag in EXPLICIT_TAGS:
        if not element_id:
            raise TreeFileError(source, f"<{tag}> needs an ID attribute naming the node type", line)
        return NodeDecl(element_id, tuple(attributes), children, source, line, explicit_tag=tag)
    if tag == "SubTree":
        if not element_id:
            raise TreeFileError(source, "<SubTree> needs an ID attribute naming the BehaviorTree", line)
        if children:
            raise TreeFileError(source, f'<SubTree ID="{element_id}"> must not have children', line)
        return NodeDecl("SubTree", tuple(attributes), (), source, line, subtree_id=element_id)
    if element_id is not None:
        raise TreeFileError(source, f"attribute ID is not allowed in <{tag}> (only in <Action ID=...> etc.)", line)
    return NodeDecl(tag, tuple(attributes), children, source, line)


def _model(element: Element, source: str) -> ModelDecl:
    line = _line(element)
    node_id = element.attrib.get("ID")
    if not node_id:
        raise TreeFileError(source, f"<{element.tag}> in <TreeNodesModel> needs an ID attribute", line)
    ports = []
    for port in _children(element):
        if port.tag in _PORT_TAGS:
            name = port.attrib.get("name")
            if not name:
                raise TreeFileError(source, f"<{port.tag}> needs a name attribute", _line(port))
            ports.append(
                ModelPort(
                    name,
                    _PORT_TAGS[port.tag],
                    port.attrib.get("type"),
                    port.attrib.get("default"),
                    (port.text or "").strip(),
                    _line(port),
                )
            )
        elif port.tag not in ("description", "MetadataFields"):
            raise TreeFileError(source, f"unexpected <{port.tag}> in the model of {node_id}", _line(port))
    return ModelDecl(element.tag, node_id, tuple(ports), source, line)


def read_xml(data: bytes, source: str) -> Document:
    """Parse one XML file (includes are listed, not followed: the loader follows them)."""
    root = parse_xml(data, source)
    line = _line(root)
    if root.tag != "root":
        raise TreeFileError(source, f'the top element must be <root BTCPP_format="4">, not <{root.tag}>', line)
    version = root.attrib.get("BTCPP_format")
    if version is None:
        logger.warning("%s: <root> has no BTCPP_format attribute; reading it as version 4", source)
    elif version.strip() != "4":
        raise TreeFileError(
            source, f'BTCPP_format="{version}" is not supported; bt_grasp reads BehaviorTree.CPP v4 files', line
        )
    document = Document(
        source, main_tree=root.attrib.get("main_tree_to_execute"), format_version=version, root_line=line
    )
    elements = _children(root)
    tree_elements = [e for e in elements if e.tag == "BehaviorTree"]
    for element in elements:
        tag, eline = element.tag, _line(element)
        if tag == "BehaviorTree":
            tree_id = element.attrib.get("ID")
            if not tree_id:
                if len(tree_elements) > 1:
                    raise TreeFileError(source, "a <BehaviorTree> needs an ID when the file has several", eline)
                tree_id = "BehaviorTree_0"
            kids = _children(element)
            if len(kids) != 1:
                raise TreeFileError(
                    source, f'<BehaviorTree ID="{tree_id}"> must have exactly 1 child, found {len(kids)}', eline
                )
            document.add_tree(TreeDecl(tree_id, _node(kids[0], source), source, eline))
        elif tag == "include":
            path = element.attrib.get("path")
            if not path:
                raise TreeFileError(source, "<include> needs a path attribute", eline)
            if "ros_pkg" in element.attrib:
                raise TreeFileError(source, "<include ros_pkg=...> is not supported (no ROS here)", eline)
            document.includes.append(IncludeDecl(path, source, eline))
        elif tag == "TreeNodesModel":
            for model in _children(element):
                if model.tag not in _MODEL_TAGS:
                    raise TreeFileError(source, f"unexpected <{model.tag}> in <TreeNodesModel>", _line(model))
                document.models.append(_model(model, source))
        else:
            raise TreeFileError(
                source, f"unexpected <{tag}> under <root>; expected BehaviorTree, include or TreeNodesModel", eline
            )
    return document
