"""The YAML twin of the XML format (see docs/tree-format.md)::

    btcpp_format: 4
    main_tree_to_execute: MainTree
    include: [grasp.xml]
    trees:
      MainTree:
        Sequence:
          name: pick
          children:
            - Approach: {target: "{object}"}
            - SubTree: {ID: Grasp, object: "{object}"}
            - AlwaysSuccess
    models:
      - {kind: Action, ID: Approach, ports: [{name: target, direction: input, type: str}]}

A node is a node type alone (``AlwaysSuccess``) or a one-key mapping from the type to its attributes, with
its children under ``children``. Only plain data is read (safe loading): tags such as ``!!python/object``
and aliases are errors, reported with their line.
"""

from __future__ import annotations

import re

import yaml

from bt_grasp.errors import TreeFileError
from bt_grasp.files import bounded_yaml
from bt_grasp.tree.formats.document import Document, IncludeDecl, ModelDecl, ModelPort, NodeDecl, TreeDecl

_PLAIN_TAGS = frozenset("tag:yaml.org,2002:" + t for t in ("map", "seq", "str", "int", "float", "bool", "null"))
_TOP_KEYS = ("btcpp_format", "main_tree_to_execute", "include", "trees", "models")
_MODEL_KEYS = ("kind", "ID", "ports", "description")
_PORT_KEYS = ("name", "direction", "type", "default", "description")
_INT = re.compile(r"-?(0|[1-9][0-9]*)")


class _Reader:
    def __init__(self, source: str) -> None:
        self.source = source
        self.seen: set[int] = set()
        self.key_nodes: dict[int, yaml.Node] = {}
        self.constructor = yaml.constructor.SafeConstructor()

    def error(self, node: yaml.Node | None, problem: str) -> TreeFileError:
        line = node.start_mark.line + 1 if node is not None and node.start_mark else None
        return TreeFileError(self.source, problem, where=line)

    def check(self, node: yaml.Node) -> None:
        if id(node) in self.seen:
            raise self.error(node, "YAML aliases (*name) are not supported in tree files")
        self.seen.add(id(node))
        if node.tag not in _PLAIN_TAGS:
            raise self.error(node, f"YAML tag {node.tag} is not allowed; a tree file holds plain data only")

    def mapping(self, node: yaml.Node, what: str) -> list[tuple[str, yaml.Node]]:
        self.check(node)
        if not isinstance(node, yaml.MappingNode):
            raise self.error(node, f"{what} must be a mapping")
        items: list[tuple[str, yaml.Node]] = []
        for key_node, value_node in node.value:
            key = self.scalar(key_node, f"a key of {what}")
            if not isinstance(key, str):
                raise self.error(key_node, f"keys of {what} must be text, got {key!r}")
            if any(k == key for k, _ in items):
                raise self.error(key_node, f"{what} has the key '{key}' twice")
            self.key_nodes[id(value_node)] = key_node
            items.append((key, value_node))
        return items

    def key_node(self, value_node: yaml.Node) -> yaml.Node:
        return self.key_nodes.get(id(value_node), value_node)

    def sequence(self, node: yaml.Node, what: str) -> list[yaml.Node]:
        self.check(node)
        if not isinstance(node, yaml.SequenceNode):
            raise self.error(node, f"{what} must be a list")
        return list(node.value)

    def scalar(self, node: yaml.Node, what: str) -> object:
        self.check(node)
        if not isinstance(node, yaml.ScalarNode):
            raise self.error(node, f"{what} must be a single value, not a {type(node).__name__[:-4].lower()}")
        return self.constructor.construct_object(node, deep=True)

    def text(self, node: yaml.Node, what: str) -> str:
        value = self.scalar(node, what)
        if value is None:
            raise self.error(node, f"{what} has no value")
        if isinstance(value, bool):
            return "true" if value else "false"
        if isinstance(value, int | float | str):
            return str(value)
        raise self.error(node, f"{what} must be text or a number, got {type(value).__name__}")

    # ---- nodes ---------------------------------------------------------------------------------
    def node(self, node: yaml.Node) -> NodeDecl:
        line = node.start_mark.line + 1
        if isinstance(node, yaml.ScalarNode):
            type_id = self.text(node, "a node")
            if type_id == "SubTree":
                raise self.error(node, "SubTree needs an ID: write SubTree: {ID: TreeName}")
            return NodeDecl(type_id, (), (), self.source, line)
        items = self.mapping(node, "a node")
        if len(items) != 1:
            raise self.error(node, f"a node is one 'Type: attributes' pair, found keys {[k for k, _ in items]}")
        type_id, body = items[0]
        attributes: list[tuple[str, str]] = []
        children: list[NodeDecl] = []
        subtree_id: str | None = None
        empty_body = isinstance(body, yaml.ScalarNode) and body.tag.endswith(":null")
        if empty_body:
            self.check(body)
        else:
            for key, value in self.mapping(body, f"the attributes of {type_id}"):
                if key == "children":
                    children = [self.node(c) for c in self.sequence(value, f"the children of {type_id}")]
                elif key == "ID" and type_id == "SubTree":
                    subtree_id = self.text(value, "the SubTree ID")
                elif isinstance(value, yaml.MappingNode):
                    quoted = f'{key}: "{{...}}"'
                    raise self.error(value, f"the value of '{key}' is a YAML mapping; quote references: {quoted}")
                else:
                    attributes.append((key, self.text(value, f"attribute '{key}'")))
        if type_id == "SubTree":
            if not subtree_id:
                raise self.error(node, "SubTree needs an ID: write SubTree: {ID: TreeName}")
            if children:
                raise self.error(node, f"SubTree {subtree_id} must not have children")
            return NodeDecl("SubTree", tuple(attributes), (), self.source, line, subtree_id=subtree_id)
        return NodeDecl(type_id, tuple(attributes), tuple(children), self.source, line)

    def model(self, node: yaml.Node) -> ModelDecl:
        fields = dict(self.mapping(node, "a model"))
        for key in fields:
            if key not in _MODEL_KEYS:
                raise self.error(
                    self.key_node(fields[key]), f"unknown key '{key}' in a model; expected {', '.join(_MODEL_KEYS)}"
                )
        if "kind" not in fields or "ID" not in fields:
            raise self.error(node, "a model needs kind and ID")
        ports = []
        for port_node in self.sequence(fields["ports"], "ports") if "ports" in fields else []:
            pf = dict(self.mapping(port_node, "a model port"))
            for key in pf:
                if key not in _PORT_KEYS:
                    raise self.error(
                        self.key_node(pf[key]), f"unknown key '{key}' in a port; expected {', '.join(_PORT_KEYS)}"
                    )
            if "name" not in pf:
                raise self.error(port_node, "a model port needs a name")
            ports.append(
                ModelPort(
                    self.text(pf["name"], "name"),
                    self.text(pf["direction"], "direction") if "direction" in pf else "input",
                    self.text(pf["type"], "type") if "type" in pf else None,
                    self.text(pf["default"], "default") if "default" in pf else None,
                    self.text(pf["description"], "description") if "description" in pf else "",
                    port_node.start_mark.line + 1,
                )
            )
        kind = self.text(fields["kind"], "kind")
        if kind not in ("Action", "Condition", "Control", "Decorator", "SubTree"):
            raise self.error(fields["kind"], f"kind must be Action, Condition, Control, Decorator or SubTree: {kind}")
        return ModelDecl(kind, self.text(fields["ID"], "ID"), tuple(ports), self.source, node.start_mark.line + 1)


def read_yaml(data: bytes, source: str) -> Document:
    """Parse one YAML tree file (includes are listed, not followed)."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise TreeFileError(source, "the file is not UTF-8 text", where=line) from None
    def refused(problem: str, line: int | None) -> TreeFileError:
        return TreeFileError(source, f"malformed YAML: {problem}", where=line)

    try:  # bounded: nesting depth and alias expansion (bt_grasp.files.bounded_yaml); aliases are refused below
        root = bounded_yaml.compose(text, yaml.SafeLoader, refused)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        mark_line = mark.line + 1 if mark else None
        raise TreeFileError(source, f"malformed YAML: {exc.problem or exc.context}", where=mark_line) from None
    except yaml.YAMLError as exc:
        position = getattr(exc, "position", None)
        line = text[:position].count("\n") + 1 if isinstance(position, int) else 1
        raise TreeFileError(source, f"malformed YAML: {getattr(exc, 'reason', exc)}", where=line) from None
    if root is None:
        raise TreeFileError(source, "the file is empty; expected a mapping with 'trees'", where=1)
    for event in yaml.parse(text, Loader=yaml.SafeLoader):
        if isinstance(event, yaml.AliasEvent):
            alias_line = event.start_mark.line + 1 if event.start_mark else None
            raise TreeFileError(source, "YAML aliases (*name) are not supported in tree files", where=alias_line)
    reader = _Reader(source)
    top = reader.mapping(root, "the file")
    fields = dict(top)
    for key, _ in top:
        if key not in _TOP_KEYS:
            raise reader.error(reader.key_node(fields[key]), f"unknown key '{key}'; expected {', '.join(_TOP_KEYS)}")
    version = reader.text(fields["btcpp_format"], "btcpp_format") if "btcpp_format" in fields else "4"
    if version != "4":
        raise reader.error(fields["btcpp_format"], f"btcpp_format {version} is not supported; use 4")
    main_node = fields.get("main_tree_to_execute")
    main = reader.text(main_node, "main_tree_to_execute") if main_node is not None else None
    document = Document(source, main_tree=main, format_version=version, root_line=root.start_mark.line + 1)
    if "trees" not in fields:
        raise reader.error(root, "the file has no 'trees'")
    for tree_id, tree_node in reader.mapping(fields["trees"], "trees"):
        document.add_tree(TreeDecl(tree_id, reader.node(tree_node), source, tree_node.start_mark.line + 1))
    if "include" in fields:
        for inc in reader.sequence(fields["include"], "include"):
            document.includes.append(IncludeDecl(reader.text(inc, "an include"), source, inc.start_mark.line + 1))
    if "models" in fields:
        document.models.extend(reader.model(m) for m in reader.sequence(fields["models"], "models"))
    return document


# ---- writing ---------------------------------------------------------------------------------------
def _yaml_value(text: str) -> int | bool | str:
    if _INT.fullmatch(text):
        return int(text)
    if text in ("true", "false"):
        return text == "true"
    return text


def _node_data(decl: NodeDecl) -> dict[str, object] | str:
    body: dict[str, object] = {}
    if decl.subtree_id is not None:
        body["ID"] = decl.subtree_id
    for key, value in decl.attributes:
        body[key] = _yaml_value(value)
    if decl.children:
        body["children"] = [_node_data(c) for c in decl.children]
    return {decl.type_id: body} if body else decl.type_id


def write_yaml(document: Document) -> str:
    data: dict[str, object] = {"btcpp_format": 4}
    if document.main_tree is not None:
        data["main_tree_to_execute"] = document.main_tree
    if document.includes:
        data["include"] = [inc.path for inc in document.includes]
    data["trees"] = {tree_id: _node_data(tree.root) for tree_id, tree in document.trees.items()}
    if document.models:
        models = []
        for model in document.models:
            ports = []
            for port in model.ports:
                entry: dict[str, object] = {"name": port.name, "direction": port.direction}
                if port.type_name:
                    entry["type"] = port.type_name
                if port.default is not None:
                    entry["default"] = port.default
                if port.description:
                    entry["description"] = port.description
                ports.append(entry)
            models.append({"kind": model.kind, "ID": model.node_id, "ports": ports})
        data["models"] = models
    return yaml.safe_dump(data, sort_keys=False, default_flow_style=False, allow_unicode=True, width=110)
