"""Declaring a node type: the class decorators and port constructors of :mod:`bt_grasp.nodes`.

The declaration is the node's manifest (BT.CPP's ``providedPorts()`` plus its registration kind): its name, its
ports, the failure reasons it may report, whether it needs the robot. It is stored on the class; registering
the class (``registry.register(MyNode)``) puts it into a registry. bt_grasp's own nodes, the built-ins included,
are declared with these same calls.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import TypeVar

from bt_grasp.tree.control_node import Control
from bt_grasp.tree.decorator_node import Decorator
from bt_grasp.tree.exceptions import DeclarationError
from bt_grasp.tree.kinds import NodeKind, PortDirection
from bt_grasp.tree.leaf_node import Leaf
from bt_grasp.tree.reasons import Reason, ReasonLike, reason_name
from bt_grasp.tree.registry import NO_DEFAULT, NodeSpec, PortSpec

L = TypeVar("L", bound=Leaf)
C = TypeVar("C", bound=Control)
D = TypeVar("D", bound=Decorator)


def input_port(
    name: str, type: type = str, default: object = NO_DEFAULT, description: str = "", *, required: bool = False,
    choices: Iterable[str] = (), reason: bool = False,
) -> PortSpec:
    """BT.CPP's ``InputPort<T>(name, default, description)``. Without a default the port is optional, as in BT.CPP:
    ``self.ports.get(name)`` is None until the tree gives it a value. ``required=True``: a tree that leaves it
    out is refused at load. ``choices``: the only literals it accepts. ``reason``: a literal must name a failure
    reason the registry knows (``FailureIs``)."""
    return PortSpec(name, PortDirection.INPUT, type, default, description, tuple(choices), reason, required)


def output_port(name: str, type: type = object, description: str = "", *, default: str | None = None) -> PortSpec:
    """BT.CPP's ``OutputPort<T>(name, description)``: the tree connects it to a blackboard entry (``grasp="{grasp}"``);
    ``default`` (``"{grasp}"``) is the entry when the tree says nothing. Any class may travel this way; an output
    port left unconnected is written nowhere (``ports.set`` returns False)."""
    return PortSpec(name, PortDirection.OUTPUT, type, NO_DEFAULT if default is None else default, description)


def inout_port(
    name: str, type: type = object, description: str = "", *, default: object = NO_DEFAULT, required: bool = False,
) -> PortSpec:
    """BT.CPP's ``BidirectionalPort<T>``: read and written through one blackboard entry."""
    return PortSpec(name, PortDirection.INOUT, type, default, description, required=required)


def _describe(cls: type, description: str | None) -> str:
    if description is not None:
        return description
    doc = (cls.__doc__ or "").strip().splitlines()
    return doc[0] if doc else ""


def _store(cls: type, spec: NodeSpec) -> None:
    cls.bt_spec = spec  # type: ignore[attr-defined]  # the manifest, read by NodeRegistry.register


def _leaf(kind: NodeKind, name: str | None, ports: Iterable[PortSpec], reasons: Iterable[ReasonLike],
          needs_robot: bool, description: str | None) -> Callable[[type[L]], type[L]]:
    reasons = tuple(reasons)

    def declare(cls: type[L]) -> type[L]:
        if not (isinstance(cls, type) and issubclass(cls, Leaf)):
            raise DeclarationError(f"@{kind.value.lower()} declares a subclass of Leaf (or RobotLeaf), not {cls!r}")
        _store(cls, NodeSpec(
            name or cls.__name__, kind, tuple(ports), cls, _describe(cls, description), needs_robot,
            failure_reasons=tuple(reason_name(r) for r in reasons),
            declared_reasons=tuple(r for r in reasons if isinstance(r, Reason)),
        ))
        return cls

    return declare


def action(
    *, name: str | None = None, ports: Iterable[PortSpec] = (), reasons: Iterable[ReasonLike] = (),
    needs_robot: bool = False, description: str | None = None,
) -> Callable[[type[L]], type[L]]:
    """Declare a :class:`Leaf` that acts (BT.CPP's ``ActionNode``).

    ``name``: the ID tree files use (the class name by default); ``ports``: its ports (``input_port`` ...);
    ``reasons``: the failure reasons it may report (a :class:`Reason` it declares is registered with it; a dry
    run's stand-in fails with them); ``needs_robot``: it uses the cell (robot, camera, planner): it then updates
    at most once per control period and ``tree run --dry`` replaces it by a stand-in; ``description``: one
    sentence (the docstring's first line by default)."""
    return _leaf(NodeKind.ACTION, name, ports, reasons, needs_robot, description)


def condition(
    *, name: str | None = None, ports: Iterable[PortSpec] = (), reasons: Iterable[ReasonLike] = (),
    needs_robot: bool = False, description: str | None = None,
) -> Callable[[type[L]], type[L]]:
    """Declare a :class:`Leaf` that checks something (BT.CPP's ``ConditionNode``: SUCCESS or FAILURE), as
    :func:`action`."""
    return _leaf(NodeKind.CONDITION, name, ports, reasons, needs_robot, description)


def control(
    *, name: str | None = None, ports: Iterable[PortSpec] = (), description: str | None = None,
    children: tuple[int, int | None] = (1, None),
) -> Callable[[type[C]], type[C]]:
    """Declare a :class:`Control` (BT.CPP's ``ControlNode``); ``children``: the least and most children it takes
    (None: no limit)."""

    def declare(cls: type[C]) -> type[C]:
        if not (isinstance(cls, type) and issubclass(cls, Control)):
            raise DeclarationError(f"@control declares a subclass of Control, not {cls!r}")
        _store(cls, NodeSpec(name or cls.__name__, NodeKind.CONTROL, tuple(ports), cls, _describe(cls, description),
                             children=children))
        return cls

    return declare


def decorator(
    *, name: str | None = None, ports: Iterable[PortSpec] = (), description: str | None = None,
) -> Callable[[type[D]], type[D]]:
    """Declare a :class:`Decorator` (BT.CPP's ``DecoratorNode``: exactly one child)."""

    def declare(cls: type[D]) -> type[D]:
        if not (isinstance(cls, type) and issubclass(cls, Decorator)):
            raise DeclarationError(f"@decorator declares a subclass of Decorator, not {cls!r}")
        _store(cls, NodeSpec(name or cls.__name__, NodeKind.DECORATOR, tuple(ports), cls,
                             _describe(cls, description)))
        return cls

    return declare
