"""The node registry: which node types a tree file may name, their ports, and how to build them.

A node type is a class declared with one of the decorators of :mod:`bt_grasp.nodes` (``@action``,
``@condition``, ``@control``, ``@decorator``: the declaration is its manifest, as BT.CPP's
``providedPorts()``) and registered with ``registry.register(MyNode)`` (BT.CPP's ``registerNodeType<T>``);
a simple leaf is a function and a port list (``registry.register_simple_action``). bt_grasp's own nodes are
declared and registered exactly so. :class:`NodeSpec` and :class:`PortSpec` are the registry's records of
those declarations; nobody writes them by hand.

Node types come only from a registry, never from dotted paths or ``eval`` of tree-file text. There is no
process-global registry: every caller builds (or copies) its own.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Final

from bt_grasp.errors import closest_names
from bt_grasp.tree.exceptions import DeclarationError, TreeRuntimeError
from bt_grasp.tree.kinds import NodeKind, PortDirection
from bt_grasp.tree.leaf_node import SimpleLeaf, SimpleTick
from bt_grasp.tree.reasons import Reason, ReasonLike, reason_name
from bt_grasp.tree.values import convert_text

if TYPE_CHECKING:
    from bt_grasp.tree.context import NodeContext
    from bt_grasp.tree.node import BtNode

__all__ = [
    "NO_DEFAULT",
    "RESERVED_ATTRIBUTES",
    "NodeKind",
    "NodeRegistry",
    "NodeSpec",
    "PortDirection",
    "PortSpec",
    "is_text_port_type",
    "model_type_name",
]


class _NoDefault:
    """Marker type of :data:`NO_DEFAULT`: the port has no default (BT.CPP's port declared without one)."""

    _instance: _NoDefault | None = None

    def __new__(cls) -> _NoDefault:
        if cls._instance is None:
            cls._instance = super().__new__(cls)
        return cls._instance

    def __repr__(self) -> str:
        return "NO_DEFAULT"


#: the default of a port declared without one
NO_DEFAULT: Final = _NoDefault()

#: the Python types a literal in a tree file converts to without help; ``object`` means "any value, as text"
TEXT_TYPES: tuple[type, ...] = (str, int, float, bool, object)
#: the C++ names Groot2 and BT.CPP print for bt_grasp's scalar port types (``tree models``, warnings)
_GROOT_NAMES: dict[type, str] = {int: "int", float: "double", bool: "bool", str: "std::string"}


def is_text_port_type(kind: type) -> bool:
    """An application type a literal can be written as (BT.CPP's ``convertFromString<T>``): a class with a
    classmethod ``from_port_text(text) -> instance`` that raises ValueError with one sentence on malformed
    text (e.g. ``bt_grasp.behaviours.pose.Pose`` for ``"0.35;-0.25;0.0;90"``)."""
    return callable(getattr(kind, "from_port_text", None))


def model_type_name(kind: type) -> str | None:
    """The type name Groot2's TreeNodesModel uses for a port type: ``int``, ``double``, ``bool``,
    ``std::string``, an application class by its name (``Pose``); None for ``object`` (any value)."""
    if kind is object:
        return None
    return _GROOT_NAMES.get(kind, kind.__name__)


#: attribute names a port may not use (BT.CPP reserves the same ones)
RESERVED_ATTRIBUTES: frozenset[str] = frozenset(
    {"ID", "name", "_description", "_autoremap", "_uid", "_fullpath"}
    | {"_failureIf", "_successIf", "_skipIf", "_while"}
    | {"_onSuccess", "_onFailure", "_onHalted", "_post"}
)


def _is_reference(text: str) -> bool:
    stripped = text.strip()
    return stripped in ("{=}", "=") or (len(stripped) >= 3 and stripped[0] == "{" and stripped[-1] == "}") or (
        stripped.startswith("${") and stripped.endswith("}"))


@dataclass(frozen=True)
class PortSpec:
    """One port of a node type, as :func:`bt_grasp.nodes.input_port` (and ``output_port``, ``inout_port``)
    declare it.

    Attributes:
        name: the XML attribute name (``target``)
        direction: INPUT, OUTPUT or INOUT
        type: the value's type: ``str``, ``int``, ``float``, ``bool``, ``object`` (any value) or an application
            class; a literal in a tree file must convert to it (a class with ``from_port_text``), any class may
            travel through the blackboard
        default: used when the tree file does not give the port (a blackboard reference such as ``"{target}"``
            or a literal); :data:`NO_DEFAULT`: none, the port has no value until the tree gives it one
        description: one sentence shown by ``bt-grasp tree show`` and written to TreeNodesModel
        choices: when not empty, the only literal values the port accepts (``else`` of Precondition)
        reason: the port names a failure reason: a literal must be one the registry knows (``FailureIs``)
        required: bt_grasp's stricter choice for an input: a tree that leaves the port out is refused at load
            (BT.CPP would fail at the first tick, when the node reads it)
    """

    name: str
    direction: PortDirection
    type: type = str
    default: object = NO_DEFAULT
    description: str = ""
    choices: tuple[str, ...] = ()
    reason: bool = False
    required: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name or not self.name[0].isalpha():
            raise DeclarationError(f"port name {self.name!r} is empty or does not start with a letter")
        if self.name in RESERVED_ATTRIBUTES or not self.name.replace("_", "a").isalnum():
            raise DeclarationError(f"port name {self.name!r} is reserved or not letters, digits and underscores")
        if not isinstance(self.direction, PortDirection):
            raise DeclarationError(f"port {self.name!r}: direction must be a PortDirection, got {self.direction!r}")
        if not isinstance(self.type, type):
            raise DeclarationError(f"port {self.name!r}: type must be a class (str, int, float, bool, object or "
                                   f"your own), got {self.type!r}")
        if self.default is None:
            raise DeclarationError(f"port {self.name!r}: default=None: leave the default out (a port declared "
                                   "without one is optional, as in BT.CPP; ports.get() returns None while unset)")
        if self.required and (self.direction is PortDirection.OUTPUT or self.default is not NO_DEFAULT):
            raise DeclarationError(f"port {self.name!r}: required=True is for an input port with no default")
        if isinstance(self.default, str):
            self._check_default(self.default)

    def _check_default(self, text: str) -> None:
        """A default written as text must convert to the port's type now, not when a tree uses it."""
        if _is_reference(text):
            return
        if self.direction is PortDirection.OUTPUT:
            raise DeclarationError(f"output port {self.name!r}: the default must be a blackboard reference such as "
                                   f"'{{{self.name}}}', got {text!r}")
        if not self.text_type:
            raise DeclarationError(f"port {self.name!r}: the default {text!r} is text, but a {self.type.__name__} "
                                   "cannot be read from text (give it from_port_text, or a default such as "
                                   f"'{{{self.name}}}')")
        try:
            value = convert_text(text, self.type)
        except TreeRuntimeError as exc:
            raise DeclarationError(f"port {self.name!r}: the default {text!r} is not a {self.type_label} "
                                   f"({exc})") from None
        if self.choices and value not in self.choices:
            raise DeclarationError(f"port {self.name!r}: the default {text!r} is not one of {', '.join(self.choices)}")

    @property
    def text_type(self) -> bool:
        """A literal written in a tree file converts to the port's type."""
        return self.type in TEXT_TYPES or is_text_port_type(self.type)

    @property
    def type_label(self) -> str:
        """The type as Groot2 names it (``double``, ``std::string``, ``Pose``); ``any value`` for ``object``."""
        return model_type_name(self.type) or "any value"

    @property
    def has_default(self) -> bool:
        return self.default is not NO_DEFAULT


Factory = Callable[["NodeContext"], "BtNode"]

_DEFAULT_CHILDREN: dict[NodeKind, tuple[int, int | None]] = {
    NodeKind.ACTION: (0, 0),
    NodeKind.CONDITION: (0, 0),
    NodeKind.CONTROL: (1, None),
    NodeKind.DECORATOR: (1, 1),
    NodeKind.SUBTREE: (0, 0),
}


@dataclass(frozen=True)
class NodeSpec:
    """A registered node type: what its declaration says (BT.CPP's ``TreeNodeManifest``).

    Attributes:
        name: the registration ID used in tree files (``RetryUntilSuccessful``)
        kind: ACTION, CONDITION, CONTROL, DECORATOR or SUBTREE
        ports: the ports the node accepts; any other attribute in a tree file is a load error
        factory: ``factory(ctx)`` returns the node (a :class:`bt_grasp.tree.node.BtNode`)
        description: one sentence for ``tree show`` and TreeNodesModel
        needs_robot: the node talks to the robot or camera; ``tree run --dry`` replaces it by a stand-in
        children: ``(min, max)`` number of children, ``max`` None for unbounded; defaults from ``kind``
        failure_reasons: the names of the reasons the leaf may fail with (its own and those of the jobs it runs);
            a dry run's stand-in fails with them (``tree run --dry --outcome``, ``--random``)
        declared_reasons: the :class:`Reason` values the declaration named (registered with the node when the
            registry does not know them yet)
    """

    name: str
    kind: NodeKind
    ports: tuple[PortSpec, ...] = ()
    factory: Factory | None = None
    description: str = ""
    needs_robot: bool = False
    children: tuple[int, int | None] | None = None
    failure_reasons: tuple[str, ...] = ()
    declared_reasons: tuple[Reason, ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name or not self.name.replace("_", "a").isalnum():
            raise DeclarationError(f"node name {self.name!r} must be letters, digits and underscores")
        if not isinstance(self.kind, NodeKind):
            raise DeclarationError(f"node {self.name!r}: kind must be a NodeKind, got {self.kind!r}")
        if self.children is None:
            object.__setattr__(self, "children", _DEFAULT_CHILDREN[self.kind])
        object.__setattr__(self, "ports", tuple(self.ports))
        for port in self.ports:
            if not isinstance(port, PortSpec):
                raise DeclarationError(f"node {self.name!r}: a port must come from input_port, output_port or "
                                       f"inout_port, got {port!r}")
        names = [p.name for p in self.ports]
        if len(set(names)) != len(names):
            raise DeclarationError(f"node {self.name!r} declares a port twice: {names}")
        reasons = tuple(reason_name(r) for r in self.failure_reasons)  # a Reason or FailureReason: its name
        for reason in reasons:
            Reason(reason)  # the name's form (DeclarationError otherwise)
        object.__setattr__(self, "failure_reasons", tuple(dict.fromkeys(reasons)))

    def port(self, name: str) -> PortSpec | None:
        for p in self.ports:
            if p.name == name:
                return p
        return None

    @property
    def min_children(self) -> int:
        assert self.children is not None
        return self.children[0]

    @property
    def max_children(self) -> int | None:
        assert self.children is not None
        return self.children[1]


def declared_spec(node_class: object) -> NodeSpec:
    """The manifest a node class's declaration (``@action`` ...) stored on it; DeclarationError when the class
    itself was not declared (a subclass of a declared node is a new node type: declare it too)."""
    spec = node_class.__dict__.get("bt_spec") if isinstance(node_class, type) else None
    if isinstance(spec, NodeSpec):
        return spec
    if isinstance(node_class, NodeSpec):
        cls = node_class.factory
        name = cls.__name__ if isinstance(cls, type) else node_class.name
        raise DeclarationError(f"register() takes the node class, not its spec: registry.register({name}) (BT.CPP's "
                               "registerNodeType<T>)")
    if not isinstance(node_class, type):
        raise DeclarationError(f"register() takes a node class declared with @action(...), @condition(...), "
                               f"@control(...) or @decorator(...) (BT.CPP's registerNodeType<T>), got {node_class!r}")
    raise DeclarationError(f"{node_class.__name__} is not declared: decorate the class with @action(...), "
                           "@condition(...), @control(...) or @decorator(...) from bt_grasp.nodes (its manifest, as "
                           "BT.CPP's providedPorts)")


def _with_arguments(node_class: Callable[..., BtNode], args: tuple[object, ...]) -> Factory:
    """A factory passing ``args`` after the context: ``node_class(ctx, *args)``."""

    def build(ctx: NodeContext) -> BtNode:
        return node_class(ctx, *args)

    build.__name__ = getattr(node_class, "__name__", "build")
    return build


#: who registered a node or reason that came with bt_grasp itself
BT_GRASP = "bt_grasp"


class NodeRegistry:
    """Node types by registration ID, and the failure reasons leaves may report (BT.CPP's
    ``BehaviorTreeFactory``). A name registered twice raises :class:`DeclarationError` (a ``ValueError``)
    saying who registered it first."""

    def __init__(self, enums: Mapping[str, int] | None = None, reasons: Iterable[Reason] = ()) -> None:
        self._specs: dict[str, NodeSpec] = {}
        #: scripting enums (BT.CPP ``registerScriptingEnum``): identifiers scripts read as integers
        self.enums: dict[str, int] = dict(enums or {})
        self._reasons: dict[str, Reason] = {}
        #: who registered each node that did not come with bt_grasp (node name -> plugin file or entry point)
        self.origins: dict[str, str] = {}
        #: the same for failure reasons (reason name -> plugin)
        self.reason_origins: dict[str, str] = {}
        self._origin: str | None = None
        for reason in reasons:
            self.register_reason(reason)

    # ---- registering --------------------------------------------------------------------------------
    @contextlib.contextmanager
    def registering(self, origin: str) -> Iterator[NodeRegistry]:
        """What is registered inside the block is ``origin``'s (a plugin's file or entry point): named as its
        origin in ``tree models --only-plugins`` and in the error when another plugin registers the same name."""
        previous, self._origin = self._origin, origin
        try:
            yield self
        finally:
            self._origin = previous

    def origin(self, name: str) -> str:
        """Who registered the node ``name``: a plugin's file or entry point, else bt_grasp."""
        return self.origins.get(name, BT_GRASP)

    def register(self, node_class: type[BtNode], name: str | None = None, *, args: tuple[object, ...] = ()) -> NodeSpec:
        """Register a declared node class (BT.CPP's ``registerNodeType<T>(name, args...)``): under its declared
        name, or ``name``; ``args`` are passed to its constructor after the context (``MyNode(ctx, *args)``).
        The reasons its declaration names are registered with it when the registry does not know them yet."""
        spec = declared_spec(node_class)
        if name is not None and name != spec.name:
            spec = dataclasses.replace(spec, name=name)
        if args:
            spec = dataclasses.replace(spec, factory=_with_arguments(node_class, args))
        return self._add(spec)

    def register_simple_action(
        self, name: str, tick: SimpleTick, ports: Iterable[PortSpec] = (), *, reasons: Iterable[ReasonLike] = (),
        description: str = "", needs_robot: bool = False,
    ) -> NodeSpec:
        """An action from a function (BT.CPP's ``registerSimpleAction``): ``tick(node) -> Status`` runs at every
        tick; ``node`` is a :class:`bt_grasp.nodes.Leaf` (``node.ports``, ``node.blackboard``, ``node.fail``).
        As BT.CPP's SimpleActionNode it is synchronous: returning RUNNING stops the run (exit 2)."""
        return self._simple(name, NodeKind.ACTION, tick, ports, reasons, description, needs_robot)

    def register_simple_condition(
        self, name: str, tick: SimpleTick, ports: Iterable[PortSpec] = (), *, reasons: Iterable[ReasonLike] = (),
        description: str = "", needs_robot: bool = False,
    ) -> NodeSpec:
        """A condition from a function (BT.CPP's ``registerSimpleCondition``), as :meth:`register_simple_action`."""
        return self._simple(name, NodeKind.CONDITION, tick, ports, reasons, description, needs_robot)

    def _simple(self, name: str, kind: NodeKind, tick: SimpleTick, ports: Iterable[PortSpec],
                reasons: Iterable[ReasonLike], description: str, needs_robot: bool) -> NodeSpec:
        if not callable(tick):
            raise DeclarationError(f"node {name!r}: the tick function {tick!r} is not callable")
        reasons = tuple(reasons)
        doc = (getattr(tick, "__doc__", None) or "").strip().splitlines()
        spec = NodeSpec(
            name, kind, tuple(ports), functools.partial(SimpleLeaf, tick=tick, synchronous=kind is NodeKind.ACTION),
            description or (doc[0] if doc else ""), needs_robot, failure_reasons=tuple(reason_name(r) for r in reasons),
            declared_reasons=tuple(r for r in reasons if isinstance(r, Reason)),
        )
        return self._add(spec)

    def _add(self, spec: NodeSpec) -> NodeSpec:
        if spec.name in self._specs:
            raise DeclarationError(f"a node named {spec.name!r} is already registered by {self.origin(spec.name)} "
                                   f"(to replace it, call registry.unregister({spec.name!r}) first)")
        if spec.factory is None or not callable(spec.factory):
            raise DeclarationError(f"node {spec.name!r} has no factory")
        for declared in spec.declared_reasons:
            known = self._reasons.get(declared.name)
            if known is None:
                self.register_reason(declared)
        for reason in spec.failure_reasons:
            if reason not in self._reasons:
                raise DeclarationError(f"node {spec.name!r} declares the failure reason {reason!r}, which is not "
                                       "registered (declare it as a Reason(...) value, or "
                                       "registry.register_reason(...) before registry.register(...))")
        self._specs[spec.name] = spec
        if self._origin is not None:
            self.origins[spec.name] = self._origin
        return spec

    def unregister(self, name: str) -> bool:
        """Remove the node type ``name``, whoever registered it (BT.CPP's ``unregisterBuilder``): a plugin that
        brings a node of a name bt_grasp already uses (another project's ``OpenGripper``) removes the shipped one
        first, then registers its own. True when there was such a node."""
        self.origins.pop(name, None)
        return self._specs.pop(name, None) is not None

    def register_reason(self, reason: Reason | str, description: str = "") -> Reason:
        """Declare a failure reason leaves may report and ``FailureIs`` may test; a name registered twice
        raises, saying who registered it first (the built-in ones are bt_grasp's)."""
        value = reason if isinstance(reason, Reason) else Reason(reason, description)
        if value.name in self._reasons:
            first = self.reason_origins.get(value.name, BT_GRASP)
            raise DeclarationError(f"a failure reason named {value.name!r} is already registered by {first}")
        self._reasons[value.name] = value
        if self._origin is not None:
            self.reason_origins[value.name] = self._origin
        return value

    def register_enums(self, values: Mapping[str, int]) -> None:
        """Scripting enums (BT.CPP's ``registerScriptingEnum``): names scripts read as integers."""
        for key, value in values.items():
            if key in self.enums and self.enums[key] != value:
                raise DeclarationError(f"scripting enum {key!r} is already registered with value {self.enums[key]}")
            self.enums[key] = int(value)

    # ---- reading ------------------------------------------------------------------------------------
    def reason(self, name: str) -> Reason | None:
        return self._reasons.get(name)

    def reasons(self) -> tuple[Reason, ...]:
        return tuple(self._reasons[n] for n in sorted(self._reasons))

    def get(self, name: str) -> NodeSpec | None:
        return self._specs.get(name)

    def __getitem__(self, name: str) -> NodeSpec:
        return self._specs[name]

    def __contains__(self, name: object) -> bool:
        return name in self._specs

    def __len__(self) -> int:
        return len(self._specs)

    def names(self) -> tuple[str, ...]:
        return tuple(sorted(self._specs))

    def specs(self) -> tuple[NodeSpec, ...]:
        return tuple(self._specs[n] for n in self.names())

    def nearest(self, name: str, n: int = 3) -> list[str]:
        """Known names closest to ``name`` (for "did you mean ...?"), best first."""
        return closest_names(name, list(self._specs), n)

    def with_specs(self, specs: Iterable[NodeSpec]) -> NodeRegistry:
        """A registry with the same enums, reasons and origins holding ``specs`` (the same node types built
        another way: a dry run's stand-ins)."""
        twin = NodeRegistry(self.enums, self._reasons.values())
        twin.origins = dict(self.origins)
        twin.reason_origins = dict(self.reason_origins)
        for spec in specs:
            twin._specs[spec.name] = spec
        return twin

    def copy(self) -> NodeRegistry:
        return self.with_specs(self._specs.values())
