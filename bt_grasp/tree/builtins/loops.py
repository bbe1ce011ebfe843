"""BT.CPP's ``LoopNode<T>`` built-ins: LoopInt, LoopDouble, LoopString and LoopBool, declared with
:func:`~bt_grasp.tree.loop_node.loop_node` as an application declares a loop over its own type."""

from __future__ import annotations

from typing import NoReturn

from bt_grasp.tree.node_api import Loop, NodeRegistry, loop_node
from bt_grasp.tree.removed import removed
from bt_grasp.tree.values import convert_text


def _integer(text: str) -> object:
    return convert_text(text, int)


def _real(text: str) -> object:
    value = convert_text(text, float)
    assert isinstance(value, float)
    return value


def _text(text: str) -> object:
    return text


def _bool(text: str) -> object:
    return convert_text(text, bool)


LoopInt = loop_node("LoopInt", int, _integer)
LoopDouble = loop_node("LoopDouble", float, _real)
LoopString = loop_node("LoopString", str, _text)
LoopBool = loop_node("LoopBool", bool, _bool)

NODES: tuple[type[Loop], ...] = (LoopInt, LoopDouble, LoopString, LoopBool)


def register(registry: NodeRegistry) -> None:
    """The built-in loops, registered as a plugin registers its nodes."""
    for node in NODES:
        registry.register(node)


def __getattr__(name: str) -> NoReturn:
    removed(__name__, name)
