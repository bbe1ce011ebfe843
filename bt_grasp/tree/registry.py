"""The node registry: which node types a tree file may name, their ports, and how to build them.

This is the contract robot leaves are written against::

    registry = builtin_registry()

    @leaf(registry, name="Approach", ports=[PortSpec("target", PortDirection.INPUT, str)], needs_robot=True)
    class Approach(Leaf):
        ...

Node types come only from a registry, never from dotted paths or ``eval`` of tree-file text. There is no
process-global registry: every caller builds (or copies) its own.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypeVar

from bt_grasp.errors import closest_names
from bt_grasp.tree.exceptions import DeclarationError
from bt_grasp.tree.reasons import Reason, ReasonLike, reason_name

if TYPE_CHECKING:
    import py_trees

    from bt_grasp.tree.context import NodeContext


class PortDirection(enum.Enum):
    """Which way a port moves data between a node and its blackboard (BT.CPP ``PortDirection``)."""

    INPUT = "input"
    OUTPUT = "output"
    INOUT = "inout"


class NodeKind(enum.Enum):
    """The BT.CPP node category; the value is the explicit XML tag (``<Action ID=...>``)."""

    ACTION = "Action"
    CONDITION = "Condition"
    CONTROL = "Control"
    DECORATOR = "Decorator"
    SUBTREE = "SubTree"


class _NoDefault:
    """Marker type of :data:`NO_DEFAULT`: the port has no default and must be given in the tree file."""

    _instance: _NoDefault | None = None

    def __new__(cls) -> _NoDefault:
        if cls._instance is None:
            cls._instance = super().__new__(cls)
        return cls._instance

    def __repr__(self) -> str:
        return "NO_DEFAULT"


NO_DEFAULT: Any = _NoDefault()

#: the Python types a port may carry; ``object`` means "any blackboard value"
PORT_TYPES: tuple[type, ...] = (str, int, float, bool, object)


def is_text_port_type(kind: type) -> bool:
    """An application type a port may carry besides PORT_TYPES (BT.CPP's ``convertFromString<T>``): a class
    with a classmethod ``from_port_text(text) -> instance`` that raises ValueError with one sentence on
    malformed text (e.g. ``bt_grasp.behaviours.pose.Pose`` for ``"0.35;-0.25;0.0;90"``)."""
    return callable(getattr(kind, "from_port_text", None))


#: attribute names a port may not use (BT.CPP reserves the same ones)
RESERVED_ATTRIBUTES: frozenset[str] = frozenset(
    {"ID", "name", "_description", "_autoremap", "_uid", "_fullpath"}
    | {"_failureIf", "_successIf", "_skipIf", "_while"}
    | {"_onSuccess", "_onFailure", "_onHalted", "_post"}
)


@dataclass(frozen=True)
class PortSpec:
    """One port of a node type.

    Attributes:
        name: the XML attribute name (``target``)
        direction: INPUT, OUTPUT or INOUT
        type: ``str``, ``int``, ``float``, ``bool`` or ``object`` (any blackboard value, not checked)
        default: used when the tree file does not give the port; :data:`NO_DEFAULT` makes the port required.
            A string default may be a blackboard reference such as ``"{target}"``.
        description: one sentence shown by ``bt-grasp tree show`` and written to TreeNodesModel
        choices: when not empty, the only literal values the port accepts (``else`` of Precondition)
        reason: the port names a failure reason: a literal must be one the registry knows (``FailureIs``)
    """

    name: str
    direction: PortDirection
    type: type = str
    default: Any = NO_DEFAULT
    description: str = ""
    choices: tuple[str, ...] = ()
    reason: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name or not self.name[0].isalpha():
            raise DeclarationError(f"port name {self.name!r} is empty or does not start with a letter")
        if self.name in RESERVED_ATTRIBUTES or not self.name.replace("_", "a").isalnum():
            raise DeclarationError(f"port name {self.name!r} is reserved or not letters, digits and underscores")
        if not isinstance(self.direction, PortDirection):
            raise DeclarationError(f"port {self.name!r}: direction must be a PortDirection, got {self.direction!r}")
        if not isinstance(self.type, type) or (self.type not in PORT_TYPES and not is_text_port_type(self.type)):
            raise DeclarationError(
                f"port {self.name!r}: type must be one of str, int, float, bool, object, or a class with from_port_text"
            )

    @property
    def required(self) -> bool:
        return self.default is NO_DEFAULT


Factory = Callable[["NodeContext"], "py_trees.behaviour.Behaviour"]

_DEFAULT_CHILDREN: dict[NodeKind, tuple[int, int | None]] = {
    NodeKind.ACTION: (0, 0),
    NodeKind.CONDITION: (0, 0),
    NodeKind.CONTROL: (1, None),
    NodeKind.DECORATOR: (1, 1),
    NodeKind.SUBTREE: (0, 0),
}


@dataclass(frozen=True)
class NodeSpec:
    """A registered node type.

    Attributes:
        name: the registration ID used in tree files (``RetryUntilSuccessful``)
        kind: ACTION, CONDITION, CONTROL, DECORATOR or SUBTREE
        ports: the ports the node accepts; any other attribute in a tree file is a load error
        factory: ``factory(ctx)`` returns the py_trees behaviour (a :class:`bt_grasp.tree.node.BtNode`)
        description: one sentence for ``tree show`` and TreeNodesModel
        needs_robot: the node talks to the robot or camera; ``tree run --dry`` requires it substituted
        children: ``(min, max)`` number of children, ``max`` None for unbounded; defaults from ``kind``
        failure_reasons: the names of the reasons the leaf may fail with (its own and those of the jobs it runs),
            each registered in the registry it goes into; a dry run's stand-in fails with them
            (``tree run --dry --outcome``, ``--random``)
    """

    name: str
    kind: NodeKind
    ports: tuple[PortSpec, ...] = ()
    factory: Factory | None = None
    description: str = ""
    needs_robot: bool = False
    children: tuple[int, int | None] | None = None
    failure_reasons: tuple[str, ...] = ()

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
                raise DeclarationError(f"node {self.name!r}: a port must be a PortSpec, got {port!r}")
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


class NodeRegistry:
    """Node types by registration ID, and the failure reasons leaves may report. A duplicate name raises
    :class:`DeclarationError` (a ``ValueError``)."""

    def __init__(
        self, specs: Iterable[NodeSpec] = (), enums: Mapping[str, int] | None = None, reasons: Iterable[Reason] = ()
    ) -> None:
        self._specs: dict[str, NodeSpec] = {}
        #: scripting enums (BT.CPP ``registerScriptingEnum``): identifiers scripts read as integers
        self.enums: dict[str, int] = dict(enums or {})
        self._reasons: dict[str, Reason] = {}
        #: who registered each node that did not come with bt_grasp (node name -> plugin file or distribution)
        self.origins: dict[str, str] = {}
        #: the same for failure reasons (reason name -> plugin)
        self.reason_origins: dict[str, str] = {}
        for reason in reasons:
            self.register_reason(reason)
        for spec in specs:
            self.register(spec)

    def register(self, spec: NodeSpec) -> NodeSpec:
        if not isinstance(spec, NodeSpec):
            raise DeclarationError(f"register() takes a NodeSpec (e.g. MyLeaf.bt_spec), got {spec!r}")
        if spec.name in self._specs:
            raise DeclarationError(f"a node named {spec.name!r} is already registered (to replace it, call "
                                   f"registry.unregister({spec.name!r}) first)")
        if spec.factory is None or not callable(spec.factory):
            raise DeclarationError(f"node {spec.name!r} has no factory")
        for reason in spec.failure_reasons:
            if reason not in self._reasons:
                raise DeclarationError(f"node {spec.name!r} declares the failure reason {reason!r}, which is not "
                                       "registered (registry.register_reason(...) before registry.register(...))")
        self._specs[spec.name] = spec
        return spec

    def unregister(self, name: str) -> bool:
        """Remove the node type ``name``, whoever registered it (BT.CPP's ``unregisterBuilder``): a plugin that
        brings a node of a name bt_grasp already uses (another project's ``OpenGripper``) removes the shipped one
        first, then registers its own. True when there was such a node."""
        self.origins.pop(name, None)
        return self._specs.pop(name, None) is not None

    def register_reason(self, reason: Reason | str, description: str = "") -> Reason:
        """Declare a failure reason leaves may report and ``FailureIs`` may test; a name registered twice
        raises (the built-in ones included)."""
        value = reason if isinstance(reason, Reason) else Reason(reason, description)
        if value.name in self._reasons:
            raise DeclarationError(f"a failure reason named {value.name!r} is already registered")
        self._reasons[value.name] = value
        return value

    def reason(self, name: str) -> Reason | None:
        return self._reasons.get(name)

    def reasons(self) -> tuple[Reason, ...]:
        return tuple(self._reasons[n] for n in sorted(self._reasons))

    def register_enums(self, values: Mapping[str, int]) -> None:
        for key, value in values.items():
            if key in self.enums and self.enums[key] != value:
                raise ValueError(f"scripting enum {key!r} is already registered with value {self.enums[key]}")
            self.enums[key] = int(value)

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

    def copy(self) -> NodeRegistry:
        twin = NodeRegistry(self._specs.values(), self.enums, self._reasons.values())
        twin.origins = dict(self.origins)
        twin.reason_origins = dict(self.reason_origins)
        return twin


T = TypeVar("T")


def leaf(
    registry: NodeRegistry | None,
    *,
    name: str | None = None,
    kind: NodeKind = NodeKind.ACTION,
    ports: Iterable[PortSpec] = (),
    needs_robot: bool = False,
    description: str | None = None,
    reasons: Iterable[ReasonLike] = (),
) -> Callable[[T], T]:
    """Class decorator: describe a :class:`bt_grasp.tree.leaf.Leaf` subclass as a node type (``reasons``: the
    failure reasons it may report, see :attr:`NodeSpec.failure_reasons`).

    The spec is stored on the class as ``bt_spec``; with a registry it is also registered there. With
    ``None`` the caller registers later: ``registry.register(Approach.bt_spec)``.
    """

    def decorate(cls: T) -> T:
        doc = (getattr(cls, "__doc__", None) or "").strip().splitlines()
        spec = NodeSpec(
            name=name or cls.__name__,  # type: ignore[attr-defined]
            kind=kind,
            ports=tuple(ports),
            factory=cls,  # type: ignore[arg-type]
            description=description if description is not None else (doc[0] if doc else ""),
            needs_robot=needs_robot,
            failure_reasons=tuple(reason_name(r) for r in reasons),
        )
        cls.bt_spec = spec  # type: ignore[attr-defined]
        if registry is not None:
            registry.register(spec)
        return cls

    return decorate
