"""Node types from a ``<TreeNodesModel>``: what a dry run stands in for when no plugin provides the node.

A BehaviorTree.CPP project describes its nodes for Groot2 in a TreeNodesModel (Nav2's ``nav2_tree_nodes.xml``,
or the ``<TreeNodesModel>`` Groot2 saves inside a tree): each action and condition with its ports, their
directions, types and defaults. ``bt-grasp tree run --dry`` reads the models of the tree file and its includes,
and of every ``--nodes-model FILE``, and makes each ``<Action>`` and ``<Condition>`` whose ID nothing registered a
node type of those ports (:func:`model_specs`), so the tree is checked against the model (an attribute the model
does not declare is an error at its line) and runs with no Python for those leaves. Controls and decorators are
not stood in for: their behaviour is the tree's logic, which only their code knows (a plugin gives it).

Port types are Groot2's names (BT.CPP's ``demangle``): integers of any width (``int``, ``unsigned int``,
``uint16``, ``int64_t``, ``size_t`` ...), ``double``/``float``, ``bool`` and ``std::string``/``string`` keep
their type (a literal is converted as BT.CPP converts it, a blackboard entry is typed as BT.CPP types it); any
other type (``geometry_msgs::msg::PoseStamped``, ``chrono::milliseconds``) is any value. A default is the
model's ``default`` text (``""`` or none: no default); an output port's default counts only when it is a
blackboard reference (``{key}``), as in BT.CPP; a default its type cannot read (Nav2's
``numeric_limits<double>::infinity()`` for a double) is left out, as BT.CPP would only fail when a node read it and a
stand-in reads none of its inputs.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
from pathlib import Path

from bt_grasp.errors import TreeFileError
from bt_grasp.files.bounded_io import read_user_file
from bt_grasp.tree.exceptions import DeclarationError
from bt_grasp.tree.formats.document import ModelDecl, ModelPort
from bt_grasp.tree.formats.xml_format import read_xml
from bt_grasp.tree.kinds import NodeKind, PortDirection
from bt_grasp.tree.ports import blackboard_key
from bt_grasp.tree.registry import NO_DEFAULT, Factory, NodeSpec, PortSpec

#: the model kinds a dry run stands in for
STANDS_IN_FOR: dict[str, NodeKind] = {"Action": NodeKind.ACTION, "Condition": NodeKind.CONDITION}

_INTEGER = re.compile(r"^(?:u?int(?:8|16|32|64)?(?:_t)?|(?:unsigned |signed )?(?:char|short|int|long|long long)"
                      r"(?: int)?|unsigned|size_t|ssize_t|ptrdiff_t)$")
_SCALARS: dict[str, type] = {"double": float, "float": float, "bool": bool, "string": str, "str": str}
_DIRECTIONS = {"input": PortDirection.INPUT, "output": PortDirection.OUTPUT, "inout": PortDirection.INOUT}


def port_type(type_name: str | None) -> type:
    """The Python type of a model port's ``type``: int, float, bool, str, else ``object`` (any value)."""
    name = (type_name or "").strip().removeprefix("std::")
    if _INTEGER.match(name):
        return int
    return _SCALARS.get(name, object)


def _port(model: ModelDecl, port: ModelPort) -> PortSpec:
    direction = _DIRECTIONS[port.direction]
    default: object = NO_DEFAULT
    text = port.default
    # BT.CPP: an empty default is none; an output's counts only as a blackboard reference
    if text and (direction is not PortDirection.OUTPUT or blackboard_key(text, port.name) is not None):
        default = text
    kind = port_type(port.type_name)
    try:
        return PortSpec(port.name, direction, kind, default, port.description)
    except DeclarationError:
        pass
    try:  # a default its type cannot read: left out (see the module)
        return PortSpec(port.name, direction, kind, NO_DEFAULT, port.description)
    except DeclarationError as exc:
        raise TreeFileError(model.source, f"TreeNodesModel: {model.node_id}: {exc}", where=port.line or model.line)\
            from None


def model_specs(models: Iterable[ModelDecl], known: Callable[[str], bool],
                factory: Callable[[NodeSpec], Factory] | None) -> list[tuple[NodeSpec, str]]:
    """A node type for each action and condition model whose ID ``known`` does not know (the first model of an ID
    wins), built by ``factory(spec)`` (None: the specs only describe the ports); with each, where it was declared
    (``the TreeNodesModel at file:line``)."""
    found: dict[str, tuple[NodeSpec, str]] = {}
    for model in models:
        kind = STANDS_IN_FOR.get(model.kind)
        if kind is None or known(model.node_id) or model.node_id in found:
            continue
        ports = tuple(_port(model, p) for p in model.ports)
        names = [p.name for p in ports]
        twice = next((n for n in names if names.count(n) > 1), None)
        if twice is not None:
            raise TreeFileError(model.source, f"TreeNodesModel: {model.node_id} declares the port '{twice}' twice",
                                where=model.line)
        origin = f"the TreeNodesModel at {model.source}:{model.line}"
        try:
            spec = NodeSpec(model.node_id, kind, ports, None, f"stand-in from {origin}")
        except DeclarationError as exc:
            raise TreeFileError(model.source, f"TreeNodesModel: {exc}", where=model.line) from None
        if factory is not None:
            spec = NodeSpec(spec.name, spec.kind, spec.ports, factory(spec), spec.description)
        found[model.node_id] = (spec, origin)
    return list(found.values())


def read_nodes_model(path: str | Path) -> list[ModelDecl]:
    """The models of a TreeNodesModel file (``--nodes-model``): a BT.CPP XML file, ``<root>`` holding a
    ``<TreeNodesModel>`` (trees in it are ignored). Bounded read; a file without models is an error."""
    document = read_xml(read_user_file(path, error=TreeFileError), str(path))
    if not document.models:
        raise TreeFileError(path, "holds no <TreeNodesModel> entries (a nodes model is Groot2's <root><TreeNodesModel>"
                            "<Action ID=...> file, such as Nav2's nav2_tree_nodes.xml)", where=document.root_line)
    return document.models
