"""``bt-grasp tree stubs NODES.xml``: a plugin file of typed stand-ins for a TreeNodesModel's actions and
conditions, written in the one node API (``docs/own-leaves.md``), to start a port from.

Each ``<Action>``/``<Condition>`` becomes a class declared with ``@bt.action``/``@bt.condition`` and the model's
ports (``bt.input_port("hz", float, "10.0", "...")``: Groot2's types as :mod:`bt_grasp.tree.model_stand_ins` reads
them, the defaults as written), whose ``update()`` succeeds after writing each output port its type's default
(the same as a dry run's stand-in for the model); ``register(registry)`` registers them all. The file loads with
``--leaves FILE.py`` and ticks as written; replace each ``update()`` with the node's work. Controls and decorators
are listed, not written: their behaviour is the tree's logic (write them from their project's source, as
``docs/porting-btcpp.md`` does for Nav2's).

The module is imported as ``bt`` (``from bt_grasp import nodes as bt``), so a node named like one of the API's
names (``Status``) cannot shadow it; an ID that is not a Python name (a keyword) gets a class name of its own and
is registered under its ID.
"""

from __future__ import annotations

import keyword
import textwrap
from collections.abc import Iterable
from pathlib import Path

from bt_grasp.tree.formats.document import ModelDecl
from bt_grasp.tree.kinds import PortDirection
from bt_grasp.tree.model_stand_ins import STANDS_IN_FOR, model_specs
from bt_grasp.tree.registry import NodeSpec, PortSpec

_DECLARE = {"input": "input_port", "output": "output_port", "inout": "inout_port"}
_TYPE_NAMES = {int: "int", float: "float", bool: "bool", str: "str", object: "object"}
_DEFAULTS = {int: "0", float: "0.0", bool: "False", str: '""'}


def _safe(text: str) -> str:
    """A file name as the generated file's comments show it: only characters that cannot end a docstring."""
    return "".join(c if c.isalnum() or c in "._-" else "_" for c in text)


def _class_name(node_id: str) -> str:
    if node_id.isidentifier() and not keyword.iskeyword(node_id) and node_id != "bt":
        return node_id
    return "Node_" + "".join(c if c.isalnum() else "_" for c in node_id)


def _port_line(port: PortSpec) -> str:
    kind = _TYPE_NAMES.get(port.type, "object")
    args = [repr(port.name), kind]
    direction = port.direction.value
    if direction == "input":
        if port.has_default:
            args.append(repr(port.default))
        if port.description:
            args.append(("description=" if not port.has_default else "") + repr(port.description))
    else:
        if port.description:
            args.append(repr(port.description))
        if port.has_default:
            args.append(f"default={port.default!r}")
    return f"    bt.{_DECLARE[direction]}({', '.join(args)}),"


def _node_text(spec: NodeSpec, model: ModelDecl) -> list[str]:
    decorator = "action" if model.kind == "Action" else "condition"
    ports = [_port_line(p) for p in spec.ports]
    head = [f"@bt.{decorator}(ports=[", *ports, "])"] if ports else [f"@bt.{decorator}()"]
    body = [f"class {_class_name(spec.name)}(bt.Leaf):",
            f'    """Stand-in for {spec.name} ({_safe(Path(model.source).name)}:{model.line}): SUCCESS, each output '
            'port written its type\'s default."""', "", "    def update(self) -> bt.Status:"]
    for port in spec.ports:
        if port.direction is PortDirection.INPUT:
            continue
        default = _DEFAULTS.get(port.type)
        if default is None:
            body.append(f"        # self.ports.set({port.name!r}, ...)  # {model_type(model, port.name)}: any value")
        else:
            body.append(f"        self.ports.set({port.name!r}, {default})")
    body.append("        return bt.Status.SUCCESS")
    return [*head, *body]


def model_type(model: ModelDecl, port: str) -> str:
    found = next((p for p in model.ports if p.name == port), None)
    return (found.type_name if found is not None else None) or "no type"


def stubs_text(models: Iterable[ModelDecl], source: str) -> tuple[str, int]:
    """The plugin file's text for the models of ``source`` (the first model of an ID), and how many nodes it has."""
    models = list(models)

    specs = model_specs(models, lambda name: False, None)
    by_id = {m.node_id: m for m in reversed(models)}
    others = sorted({m.node_id for m in models if m.kind not in STANDS_IN_FOR and m.kind != "SubTree"})
    lines = [f'"""Stand-ins for the actions and conditions of {_safe(source)}, written by `bt-grasp tree stubs`.',
             "",
             "Each node is declared with its model's ports and succeeds, writing each output port its type's "
             "default;",
             "replace each update() with the node's work (docs/own-leaves.md). Load with --leaves THIS_FILE.py."]
    if others:
        lines += ["", *textwrap.wrap("Not written (controls and decorators: their behaviour is the tree's logic, "
                                     f"write them from their project's source): {', '.join(others)}.", 116)]
    lines += ['"""', "", "from __future__ import annotations", "", "from bt_grasp import nodes as bt", ""]
    names = []
    for spec, _ in specs:
        lines += ["", *_node_text(spec, by_id[spec.name]), ""]
        names.append(spec.name)
    lines += ["", "#: (class, the ID trees name it by)",
              "NODES = (" + "".join(f"\n    ({_class_name(n)}, {n!r})," for n in names) + ("\n)" if names else ")"),
              "", "",
              "def register(registry: bt.NodeRegistry) -> None:",
              "    \"\"\"BT.CPP's BT_REGISTER_NODES: every stand-in, under its ID.\"\"\"",
              "    for node, node_id in NODES:",
              "        registry.register(node, node_id)", ""]
    return "\n".join(lines), len(names)
