"""Helpers the node-family modules use to declare their manifests (BT.CPP ``providedPorts``)."""

from __future__ import annotations

from bt_grasp.tree.registry import NodeKind, NodeSpec, PortDirection, PortSpec

IN, OUT, INOUT = PortDirection.INPUT, PortDirection.OUTPUT, PortDirection.INOUT
#: the literal statuses a port such as Precondition's ``else`` accepts
STATUS_NAMES = ("SUCCESS", "FAILURE", "SKIPPED", "RUNNING")


def control(
    cls: type, description: str, ports: tuple[PortSpec, ...] = (), children: tuple[int, int | None] = (1, None)
) -> NodeSpec:
    return NodeSpec(cls.__name__, NodeKind.CONTROL, ports, cls, description, children=children)


def decorator(cls: type, description: str, ports: tuple[PortSpec, ...] = (), name: str | None = None) -> NodeSpec:
    return NodeSpec(name or cls.__name__, NodeKind.DECORATOR, ports, cls, description)


def action(cls: type, description: str, ports: tuple[PortSpec, ...] = (), name: str | None = None) -> NodeSpec:
    return NodeSpec(name or cls.__name__, NodeKind.ACTION, ports, cls, description)


def condition(cls: type, description: str, ports: tuple[PortSpec, ...] = (), name: str | None = None) -> NodeSpec:
    return NodeSpec(name or cls.__name__, NodeKind.CONDITION, ports, cls, description)
