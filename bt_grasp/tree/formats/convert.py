"""Convert tree files between BT.CPP v4 XML and the YAML twin format.

Both directions go through :class:`Document`, so a converted file loads to the same tree. Includes stay
references (their paths are copied as written). Comments are carried over both ways, by one rule: a comment
stands before the node that follows it in the source, and a comment before no node (the file's header, one
before ``<BehaviorTree>`` or a tree's name, one closing a block, one among a node's attributes or the models)
goes to the top of the file. An XML comment becomes ``#`` lines before its node's YAML line; in YAML, a run of
``#`` lines with no blank line between them is one comment (an XML comment's lines), a blank line starts the next,
and a comment at the end of a node's first line (``- Lift  # then up``) stands before that node. YAML comments
are found with PyYAML's scanner (what lies between its tokens), so a ``#`` inside a quoted value is not one.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections import defaultdict
from pathlib import Path

import yaml

from bt_grasp.errors import InputError
from bt_grasp.files.output_files import write_output_file
from bt_grasp.tree.formats.document import Document, NodeDecl
from bt_grasp.tree.formats.yaml_format import write_yaml
from bt_grasp.tree.loader import read_single

_PORT_TAGS = {"input": "input_port", "output": "output_port", "inout": "inout_port"}


class Comments:
    """An XML source's comments: those before a node, by the node's line, and the rest (the header)."""

    def __init__(self, before: dict[int, list[str]] | None = None, header: list[str] | None = None) -> None:
        self.before: dict[int, list[str]] = before if before is not None else {}
        self.header: list[str] = header if header is not None else []

    def take(self, decl: NodeDecl) -> list[str]:
        """The comments before ``decl`` (once: two nodes on one line do not both get them)."""
        return self.before.pop(decl.line, []) if decl.line else []


_STRUCTURE = frozenset({"root", "BehaviorTree", "TreeNodesModel", "include"})  # elements that are no node
_COMMENT = re.compile(r"<!--(.*?)-->", re.S)
_NEXT_TAG = re.compile(r"<\s*(/?)\s*([A-Za-z_][\w.:-]*)")


def xml_comments(text: str, node_lines: set[int]) -> Comments:
    """The comments of XML ``text`` (already parsed safely), each placed before the next element that starts
    after it when that element is a node (its start line in ``node_lines``), else in the header."""
    comments = Comments(defaultdict(list), [])
    for match in _COMMENT.finditer(text):
        body = match.group(1)
        following = _NEXT_TAG.search(text, match.end())
        line = text.count("\n", 0, following.start()) + 1 if following is not None else 0
        if (following is not None and not following.group(1) and following.group(2) not in _STRUCTURE
                and line in node_lines):
            comments.before[line].append(body)
        else:
            comments.header.append(body)
    comments.before = dict(comments.before)
    return comments


_YAML_COMMENT = re.compile(r"#[^\n]*")


def _xml_body(lines: list[str]) -> str:
    """A YAML comment's lines as an XML comment's text (``--`` is not allowed there: spaced out)."""
    text = "\n     ".join(lines).replace("--", "- -")
    return f" {text} " if not text.endswith("-") else f" {text}  "


def yaml_comments(text: str, node_lines: set[int]) -> Comments:
    """The ``#`` comments of YAML ``text`` (already parsed safely), placed as :func:`xml_comments` places XML
    ones: a block of full-line comments before the node whose type starts the next scalar after it (its line in
    ``node_lines``), a comment ending a node's first line before that node, any other in the header."""
    tokens = [t for t in yaml.scan(text, Loader=yaml.SafeLoader) if t.start_mark.index != t.end_mark.index
              or isinstance(t, yaml.ScalarToken)]
    comments = Comments(defaultdict(list), [])
    block: list[str] = []
    block_line = -2

    def place(lines: list[str], line: int | None) -> None:
        if lines:
            (comments.before[line] if line is not None else comments.header).append(_xml_body(lines))

    previous_end = 0
    for index, token in enumerate([*tokens, None]):
        gap_end = token.start_mark.index if token is not None else len(text)
        for match in _YAML_COMMENT.finditer(text, previous_end, gap_end):
            line = text.count("\n", 0, match.start()) + 1
            body = match.group()[1:].removeprefix(" ").rstrip()
            line_start = text.rfind("\n", 0, match.start()) + 1
            if text[line_start:match.start()].strip():  # after code on its line: about the node it ends
                place([body], line if line in node_lines else None)
                continue
            if block and line != block_line + 1:  # a blank line (or code) between: a new comment
                place(block, None)
                block = []
            block.append(body)
            block_line = line
        if block and token is not None:
            following = next((t for t in tokens[index:] if isinstance(t, yaml.ScalarToken)), None)
            line = following.start_mark.line + 1 if following is not None else 0
            place(block, line if line in node_lines and line > block_line else None)
            block = []
        if token is not None:
            previous_end = max(previous_end, token.end_mark.index)
    place(block, None)
    comments.before = dict(comments.before)
    return comments


def _node_element(decl: NodeDecl, comments: Comments | None = None) -> ET.Element:
    element = ET.Element(decl.type_id)
    if decl.subtree_id is not None:
        element.set("ID", decl.subtree_id)
    for key, value in decl.attributes:
        element.set(key, value)
    for child in decl.children:
        for body in comments.take(child) if comments is not None else ():
            element.append(ET.Comment(body))
        element.append(_node_element(child, comments))
    return element


def write_xml(document: Document, comments: Comments | None = None) -> str:
    """``document`` as BT.CPP v4 XML (compact form), with ``comments`` (an XML source's) where they were."""
    root = ET.Element("root", {"BTCPP_format": "4"})
    if document.main_tree is not None:
        root.set("main_tree_to_execute", document.main_tree)
    for inc in document.includes:
        ET.SubElement(root, "include", {"path": inc.path})
    for tree_id, tree in document.trees.items():
        tree_element = ET.SubElement(root, "BehaviorTree", {"ID": tree_id})
        for body in comments.take(tree.root) if comments is not None else ():
            tree_element.append(ET.Comment(body))
        tree_element.append(_node_element(tree.root, comments))
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
    header = "".join(f"<!--{body}-->\n" for body in (comments.header if comments is not None else ()))
    return header + ET.tostring(root, encoding="unicode") + "\n"


def _hash_lines(body: str, pad: str) -> list[str]:
    """An XML comment's text as YAML comment lines (its own indentation dropped)."""
    return [f"{pad}# {text.strip()}".rstrip() for text in body.strip().splitlines()]


def _yaml_with_comments(document: Document, comments: Comments) -> str:
    """The YAML twin with each comment as ``#`` lines before its node's line (nodes are the list items and each
    tree's root, in the order the writer emits them: depth first, as the document holds them)."""
    order: list[NodeDecl] = []

    def walk(decl: NodeDecl) -> None:
        order.append(decl)
        for child in decl.children:
            walk(child)

    for tree in document.trees.values():
        walk(tree.root)
    lines = write_yaml(document).splitlines()
    out = [text for body in comments.header for text in _hash_lines(body, "")]
    nodes = iter(order)
    in_trees = False
    for line in lines:
        indent = len(line) - len(line.lstrip())
        if indent == 0:
            in_trees = line.startswith("trees:")
        stripped = line.lstrip()
        # a list item, a tree's root (``    Sequence:``), or a tree whose root is a bare name (``  Main: Leaf``)
        is_node = in_trees and (stripped.startswith("- ") or indent == 4 or (indent == 2 and not line.endswith(":")))
        if is_node:
            decl = next(nodes, None)
            for body in comments.take(decl) if decl is not None else ():
                out.extend(_hash_lines(body, " " * indent))
        out.append(line)
    return "\n".join(out) + "\n"


def format_of(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix == ".xml":
        return "xml"
    if suffix in (".yaml", ".yml"):
        return "yaml"
    raise InputError(path, f"unknown tree file extension '{suffix}'; use .xml, .yaml or .yml")


def write_document(document: Document, fmt: str, comments: Comments | None = None) -> str:
    if fmt == "xml":
        return write_xml(document, comments)
    return write_yaml(document) if comments is None else _yaml_with_comments(document, comments)


def _node_lines(document: Document) -> set[int]:
    lines: set[int] = set()

    def walk(decl: NodeDecl) -> None:
        lines.add(decl.line)
        for child in decl.children:
            walk(child)

    for tree in document.trees.values():
        walk(tree.root)
    return lines


def convert_file(source: Path, target: Path) -> Document:
    """Read ``source`` (one file, includes not followed) and write it to ``target`` in the other format, its
    comments kept (see the module's docstring)."""

    document = read_single(source)
    text = document.texts[str(source)]  # the text read_single parsed (bounded, no DTD, no YAML tags)
    if format_of(source) == "xml":
        comments = xml_comments(text, _node_lines(document))
    else:
        comments = yaml_comments(text, _node_lines(document))
    write_output_file(target, write_document(document, format_of(target), comments), "TARGET", example="tree.yaml")
    return document
