"""Check declarations against the registry: node types, ports, attributes, child counts, scripts, models.

Every problem raises :class:`bt_grasp.errors.TreeFileError` naming the file and line; nothing here builds
or runs a node.
"""

from __future__ import annotations

import logging
import re
from dataclasses import dataclass, field

from bt_grasp.errors import TreeFileError, did_you_mean
from bt_grasp.tree.builtins import REMOVED_V3_NAMES
from bt_grasp.tree.exceptions import PortValueError, ScriptSyntaxError, TreeRuntimeError, UnknownNodes
from bt_grasp.tree.formats.document import Document, ModelDecl, NodeDecl
from bt_grasp.tree.node import POST_CONDITIONS, PRE_CONDITIONS, Conditions
from bt_grasp.tree.ports import PortValue, blackboard_key
from bt_grasp.tree.registry import NodeKind, NodeRegistry, NodeSpec, model_type_name
from bt_grasp.tree.scripting import parse_script
from bt_grasp.tree.values import convert_text as text_value

logger = logging.getLogger(__name__)

CONDITION_ATTRIBUTES = frozenset(PRE_CONDITIONS + POST_CONDITIONS)
SPECIAL_ATTRIBUTES = frozenset({"name", "_description", "_autoremap", "_uid", "_fullpath"})

_MODEL_TYPES: dict[str, type] = {
    **dict.fromkeys(
        ("int", "unsigned", "unsigned int", "long", "unsigned long", "short", "size_t", "int64_t", "uint64_t"),
        int,
    ),
    **dict.fromkeys(("double", "float"), float),
    "bool": bool,
    **dict.fromkeys(("std::string", "string", "str"), str),
}


@dataclass(frozen=True)
class ResolvedNode:
    """A declaration checked against its spec."""

    spec: NodeSpec
    name: str
    ports: dict[str, PortValue] = field(default_factory=dict)
    conditions: Conditions = field(default_factory=Conditions)
    remaps: tuple[tuple[str, str], ...] = ()  # SubTree only: port -> "{key}" or literal
    autoremap: bool = False


def article(kind: str) -> str:
    return ("an " if kind[:1] in "AEIOU" else "a ") + kind



def parse_conditions(decl: NodeDecl) -> Conditions:
    scripts = {}
    for key, value in decl.attributes:
        if key in CONDITION_ATTRIBUTES:
            try:
                scripts[key] = parse_script(value)
            except ScriptSyntaxError as exc:
                raise decl.error(f"{key}: {exc}") from None
    return Conditions(scripts)


def _unknown_node(decl: NodeDecl, registry: NodeRegistry, document: Document) -> TreeFileError:
    type_id = decl.type_id
    if type_id in REMOVED_V3_NAMES:
        return decl.error(f"'{type_id}' is a BehaviorTree.CPP 3.x node; version 4 calls it {REMOVED_V3_NAMES[type_id]}")
    if type_id in document.trees:
        return decl.error(f"'{type_id}' is a BehaviorTree; use it as <SubTree ID=\"{type_id}\"/>")
    model = next((m for m in document.models if m.node_id == type_id and m.kind != "SubTree"), None)
    if model is not None:
        where = f"{model.source}:{model.line}"
        if model.kind in ("Action", "Condition"):
            return decl.error(f"unknown node '{type_id}': the TreeNodesModel at {where} declares it, but no plugin "
                              "gives its code (`bt-grasp tree run --dry` stands in for it; `bt-grasp tree stubs` "
                              "writes a plugin to start from)")
        return decl.error(f"unknown node '{type_id}': the TreeNodesModel at {where} declares it a {model.kind}, whose "
                          "behaviour only its code knows: give it with --leaves (a dry run stands in for actions and "
                          "conditions only)")
    hint = did_you_mean(type_id, list(registry.names()))
    return decl.error(f"unknown node '{type_id}'{hint}")


def _port_listing(spec: NodeSpec) -> str:
    """``inputs: a, b; outputs: c`` (each direction that has ports), or that the node has none."""
    groups = [(label, [p.name for p in spec.ports if p.direction.value == direction])
              for label, direction in (("inputs", "input"), ("outputs", "output"), ("in/out", "inout"))]
    listed = "; ".join(f"{label}: {', '.join(names)}" for label, names in groups if names)
    return listed or f"{spec.name} has no ports"


def _edits(a: str, b: str) -> int:
    """Optimal-string-alignment distance (insertions, deletions, substitutions, swaps of neighbours)."""
    previous2: list[int] = []
    previous = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        current = [i]
        for j, cb in enumerate(b, 1):
            cost = min(previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (ca != cb))
            if i > 1 and j > 1 and ca == b[j - 2] and a[i - 2] == cb:
                cost = min(cost, previous2[j - 2] + 1)
            current.append(cost)
        previous2, previous = previous, current
    return previous[-1]


def _attribute_hint(key: str, spec: NodeSpec) -> str:
    """"; did you mean 'x' (output: ...)?" for an unknown attribute, or "".

    A misspelling (the same name but for case, or one or two letters off: ``colr``, ``_skipif``) names the
    port it misspells. Another word (``detections`` is no misspelling of ``detector``, an input choosing the
    detector) names the port whose description uses that word (``target``: "the chosen detection"), so the hint
    points the way the tree meant; else no hint (the listing of inputs and outputs is given)."""
    extras = sorted(CONDITION_ATTRIBUTES | SPECIAL_ATTRIBUTES)
    names = [p.name for p in spec.ports] + extras
    lowered = key.lower()
    allowed = 1 if len(key) <= 3 else 2
    spelled = [n for n in names if n.lower() == lowered] or sorted(
        (n for n in names if _edits(lowered, n.lower()) <= allowed), key=lambda n: _edits(lowered, n.lower()))
    if spelled:
        return did_you_mean(spelled[0], spelled[:1]) if spelled[0] in extras else _named(spec, spelled[0])
    stems = {lowered, lowered.removesuffix("s")} if len(lowered) >= 4 else set()
    for port in spec.ports:
        words = set(re.findall(r"[a-z_]+", port.description.lower()))
        if stems & (words | {w.removesuffix("s") for w in words}):
            return _named(spec, port.name)
    return ""


def _named(spec: NodeSpec, name: str) -> str:
    port = spec.port(name)
    if port is None:
        return ""
    what = f": {port.description}" if port.description else ""
    return f"; did you mean '{name}' ({port.direction.value}{what})?"


def check_known_nodes(document: Document, registry: NodeRegistry) -> None:
    """Every node type the document's trees name is registered: else one :class:`TreeFileError` (one unknown
    node) or :class:`UnknownNodes` (every unknown node, in file order, each at its file and line)."""
    problems: list[TreeFileError] = []

    def walk(decl: NodeDecl) -> None:
        if decl.type_id != "SubTree":
            spec = registry.get(decl.type_id)
            if spec is None or spec.kind is NodeKind.SUBTREE:
                problems.append(_unknown_node(decl, registry, document))
        for child in decl.children:
            walk(child)

    for tree in document.trees.values():
        walk(tree.root)
    if len(problems) == 1:
        raise problems[0]
    if problems:
        raise UnknownNodes(problems)


def resolve_node(decl: NodeDecl, registry: NodeRegistry, document: Document) -> ResolvedNode:
    """Check a (non-SubTree) declaration and type its ports."""
    spec = registry.get(decl.type_id)
    if spec is None or spec.kind is NodeKind.SUBTREE:
        raise _unknown_node(decl, registry, document)
    if decl.explicit_tag and decl.explicit_tag != spec.kind.value:
        raise decl.error(f"{spec.name} is {article(spec.kind.value)}, not {article(decl.explicit_tag)}")
    count, low, high = len(decl.children), spec.min_children, spec.max_children
    if count < low or (high is not None and count > high):
        if high == low:
            wanted = "no children" if low == 0 else f"exactly {low} child" + ("ren" if low > 1 else "")
        elif high is None:
            wanted = f"at least {low} child" + ("ren" if low > 1 else "")
        else:
            wanted = f"{low} to {high} children"
        raise decl.error(f"{spec.name} must have {wanted}, found {count}")
    ports: dict[str, PortValue] = {}
    for key, value in decl.attributes:
        if key in SPECIAL_ATTRIBUTES or key in CONDITION_ATTRIBUTES:
            continue
        port = spec.port(key)
        if port is None:
            raise decl.error(f"unknown attribute '{key}' for {spec.name} ({_port_listing(spec)})"
                             f"{_attribute_hint(key, spec)}")
        try:
            ports[key] = PortValue.from_text(port, value, f"{decl.source}:{decl.line}")
        except PortValueError as exc:
            raise decl.error(f"{spec.name}: {exc}") from None
        if port.reason and ports[key].key is None and registry.reason(str(ports[key].literal)) is None:
            hint = did_you_mean(str(ports[key].literal), [r.name for r in registry.reasons()])
            raise decl.error(f"{spec.name}: unknown failure reason '{ports[key].literal}'{hint}")
    for port in spec.ports:
        if port.name in ports:
            continue
        if port.required:
            raise decl.error(f"{spec.name} needs the port '{port.name}' ({port.description or port.type_label})")
        if not port.has_default:
            continue  # BT.CPP: an optional port; the node's ports.get() gives None
        try:
            ports[port.name] = PortValue.from_default(port)
        except PortValueError as exc:  # a plugin's default its own type refuses
            origin = registry.origin(spec.name)
            raise decl.error(f"{spec.name} (from {origin}): the default of {exc}") from None
    name = decl.name if decl.name is not None else spec.name
    return ResolvedNode(spec, name, ports, parse_conditions(decl))


def resolve_subtree(decl: NodeDecl, document: Document, spec: NodeSpec) -> ResolvedNode:
    """Check a ``<SubTree>`` reference: the tree exists, remapped ports agree with its model."""
    subtree_id = decl.subtree_id or ""
    if subtree_id not in document.trees:
        hint = did_you_mean(subtree_id, list(document.trees))
        raise decl.error(f"<SubTree> refers to an unknown BehaviorTree '{subtree_id}'{hint}")
    autoremap = False
    remaps: list[tuple[str, str]] = []
    for key, value in decl.attributes:
        if key == "_autoremap":
            try:
                autoremap = bool(text_value(value, bool))
            except TreeRuntimeError:
                raise decl.error(f"_autoremap must be true or false, got {value!r}") from None
        elif key in SPECIAL_ATTRIBUTES or key in CONDITION_ATTRIBUTES:
            continue
        elif key.startswith("_") or not key[:1].isalpha():
            raise decl.error(f"unknown attribute '{key}' for SubTree")
        else:
            remaps.append((key, value))
    model = next((m for m in document.models if m.kind == "SubTree" and m.node_id == subtree_id), None)
    if model is not None:
        known = {p.name: p for p in model.ports}
        for key, _ in remaps:
            if key not in known:  # BT.CPP remaps it all the same: worth a word, not a refusal
                logger.warning(
                    "%s:%d: SubTree %s remaps '%s', which its TreeNodesModel does not list%s",
                    decl.source, decl.line, subtree_id, key, did_you_mean(key, list(known)),
                )
        given = {k for k, _ in remaps}
        for port in model.ports:
            if port.name in given or autoremap:
                continue
            if not port.default:  # BT.CPP: an empty default="" is no default
                raise decl.error(f"SubTree {subtree_id} needs the port '{port.name}' (its TreeNodesModel says so)")
            remaps.append((port.name, port.default))
    name = decl.name if decl.name is not None else subtree_id
    return ResolvedNode(spec, name, {}, parse_conditions(decl), tuple(remaps), autoremap)


def check_models(document: Document, registry: NodeRegistry) -> None:
    """TreeNodesModel entries of registered nodes should agree with the registry. BT.CPP reads only the
    ``<SubTree>`` models and ignores the others, so a disagreement (a stand-in that declares fewer ports than
    the other project's real node, or another type) is logged as a warning naming the file and line, and the
    tree loads as BT.CPP loads it."""
    for model in document.models:
        if model.kind == "SubTree":
            continue
        spec = registry.get(model.node_id)
        if spec is None:
            continue  # Groot2 describes nodes this tree may not use; an unknown node in a tree is caught there
        for line, problem in _model_problems(model, spec):
            logger.warning("%s:%d: TreeNodesModel: %s (BT.CPP ignores it)", model.source, line, problem)


def _model_problems(model: ModelDecl, spec: NodeSpec) -> list[tuple[int, str]]:
    """Where a node's model and its registration disagree: (line, problem) pairs."""
    if spec.kind.value != model.kind:
        return [(model.line, f"{spec.name} is registered as {article(spec.kind.value)}, the model says {model.kind}")]
    problems = []
    for mport in model.ports:
        port = spec.port(mport.name)
        line = mport.line or model.line
        if port is None:
            known = ", ".join(p.name for p in spec.ports) or "none"
            problems.append((line, f"{spec.name} has no port '{mport.name}' (its ports: {known})"))
            continue
        if port.direction.value != mport.direction:
            says = f"the model says {mport.direction}"
            problems.append((line, f"port '{mport.name}' of {spec.name} is {port.direction.value}, {says}"))
            continue
        said = (mport.type_name or "").strip()
        wanted = _MODEL_TYPES.get(said)
        ours = model_type_name(port.type)
        scalar = port.type in _MODEL_TYPES.values()
        if ours is not None and said and ((wanted is not None and wanted is not port.type) or (
                wanted is None and not scalar and said.rsplit("::", 1)[-1] != ours)):
            problems.append((line, f"port '{mport.name}' of {spec.name} has type {ours}, the model says {said}"))
    return problems


#: the ports of built-in nodes that hold a script
_SCRIPT_PORTS = {"Script": "code", "ScriptCondition": "code", "Precondition": "if"}


def check_read_only_ports(document: Document) -> None:
    """A script inside a ``<BehaviorTree>`` may not assign to a port its ``<SubTree>`` TreeNodesModel declares
    as ``input_port``: the caller's entry is read-only there. Raises TreeFileError at the script's line."""
    for model in document.models:
        if model.kind != "SubTree" or model.node_id not in document.trees:
            continue
        inputs = {p.name for p in model.ports if p.direction == "input"}
        if inputs:
            _check_assignments(document.trees[model.node_id].root, inputs, model.node_id)


def _check_assignments(decl: NodeDecl, inputs: set[str], tree_id: str) -> None:
    scripts = [(k, v) for k, v in decl.attributes if k in CONDITION_ATTRIBUTES]
    port = _SCRIPT_PORTS.get(decl.type_id)
    if port is not None:
        scripts += [(port, v) for k, v in decl.attributes if k == port and blackboard_key(v, port) is None]
    for key, text in scripts:
        try:
            written = parse_script(text).assigned_names() & inputs
        except ScriptSyntaxError:
            continue  # reported with its own message by resolve_node / parse_conditions
        if written:
            name = sorted(written)[0]
            label = decl.type_id if key == port else key
            raise decl.error(
                f"{label}: script {text!r} assigns to '{name}', a read-only input port of SubTree {tree_id} "
                "(its TreeNodesModel declares input_port; declare it inout_port or output_port to write it)"
            )
    for child in decl.children:
        _check_assignments(child, inputs, tree_id)
