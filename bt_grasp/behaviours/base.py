"""The base of every robot leaf: receives the :class:`Cell` in ``setup`` and times out in simulated time."""

from __future__ import annotations

from typing import TYPE_CHECKING

from py_trees.common import Status

from bt_grasp.behaviours.reasons import ReasonLike, reason_name
from bt_grasp.tree.exceptions import TreeRuntimeError
from bt_grasp.tree.leaf import Leaf

if TYPE_CHECKING:  # the cell (numpy, the scene model) is imported when a tree is set up, not to validate it
    from bt_grasp.behaviours.cell import Cell
    from bt_grasp.perception.results import Detection


class RobotLeaf(Leaf):
    """A leaf that talks to the cell. ``__init__`` (from Leaf) stores configuration only."""

    cell: Cell

    def setup(self, **kwargs: object) -> None:
        from bt_grasp.behaviours.cell import Cell

        cell = kwargs.get("cell")
        if not isinstance(cell, Cell):
            raise TypeError(f"{self.name}: setup() needs cell=Cell(...)")
        self.cell = cell

    def now_s(self) -> float:
        return self.cell.clock.now_ns() * 1e-9

    def failed(self, reason: ReasonLike, sentence: str) -> Status:
        """Fail with a reason (built-in or registered) and one sentence; also logged to the run's media."""
        self.cell.media.log("WARN", self.name, f"{reason_name(reason)}: {sentence}")
        return self.fail(reason, sentence)

    def input(self, port: str) -> object:
        """A port's value, or None when it is not set (an empty blackboard entry)."""
        value: object = self.ports.get(port) if self.ports.has(port) else None
        return value

    def input_float(self, port: str) -> float:
        """A number port's value (the tree loader checked its type)."""
        value = self.input(port)
        if isinstance(value, bool) or not isinstance(value, int | float | str):
            raise TreeRuntimeError(f"{self.bt_path}: port '{port}' holds {value!r}, not a number")
        return float(value)

    def input_int(self, port: str) -> int:
        value = self.input(port)
        if isinstance(value, bool) or not isinstance(value, int | str):
            raise TreeRuntimeError(f"{self.bt_path}: port '{port}' holds {value!r}, not an integer")
        return int(value)

    def input_str(self, port: str) -> str:
        """A text port's value ('' when not set)."""
        value = self.input(port)
        return "" if value is None else str(value)

    def input_detection(self, port: str) -> Detection | None:
        """A perceived object from a port, or None when the port holds none."""
        from bt_grasp.perception.results import Detection

        value = self.input(port)
        return value if isinstance(value, Detection) else None

    def input_detections(self, port: str) -> tuple[Detection, ...]:
        """A list of perceived objects from a port (empty when it holds none)."""
        from bt_grasp.perception.results import Detection

        value = self.input(port)
        if isinstance(value, Detection):
            return (value,)
        if isinstance(value, tuple | list):
            return tuple(v for v in value if isinstance(v, Detection))
        return ()
