"""The base of every robot leaf: receives the :class:`Cell` in ``setup`` and times out in simulated time."""

from __future__ import annotations

from typing import Any

from py_trees.common import Status

from bt_grasp.behaviours.cell import Cell
from bt_grasp.behaviours.reasons import FailureReason
from bt_grasp.tree.leaf import Leaf


class RobotLeaf(Leaf):
    """A leaf that talks to the cell. ``__init__`` (from Leaf) stores configuration only."""

    cell: Cell

    def setup(self, **kwargs: Any) -> None:
        cell = kwargs.get("cell")
        if not isinstance(cell, Cell):
            raise TypeError(f"{self.name}: setup() needs cell=Cell(...)")
        self.cell = cell

    def now_s(self) -> float:
        return self.cell.clock.now_ns() * 1e-9

    def failed(self, reason: FailureReason, sentence: str) -> Status:
        self.cell.media.log("WARN", self.name, f"{reason.value}: {sentence}")
        return self.fail(reason.value, sentence)

    def input(self, port: str) -> Any:
        """A port's value, or None when it is not set (an empty blackboard entry)."""
        return self.ports.get(port) if self.ports.has(port) else None
