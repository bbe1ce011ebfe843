"""The base of every robot leaf: receives the :class:`Cell` in ``setup`` and times out in simulated time."""

from __future__ import annotations

from bt_grasp.behaviours.attempts import Attempt
from bt_grasp.behaviours.cell import Cell
from bt_grasp.behaviours.reasons import ReasonLike, reason_name
from bt_grasp.perception.results import Detection
from bt_grasp.tree.node_api import Leaf, Status


class RobotLeaf(Leaf):
    """A leaf that talks to the cell (declare it with ``needs_robot=True``). ``__init__`` (from Leaf) stores
    configuration only; ``setup(cell=...)`` keeps the run's services as ``self.cell``."""

    cell: Cell

    def setup(self, **kwargs: object) -> None:
        cell = kwargs.get("cell")
        if not isinstance(cell, Cell):
            raise TypeError(f"{self.name}: setup() needs cell=Cell(...)")
        self.cell = cell

    def now_s(self) -> float:
        return self.cell.clock.now_ns() * 1e-9

    def fail(self, reason: ReasonLike, sentence: str) -> Status:
        """:meth:`Leaf.fail`, the reason and sentence also logged to the run's media (the log, the live view)."""
        self.cell.media.log("WARN", self.name, f"{reason_name(reason)}: {sentence}")
        return super().fail(reason, sentence)

    def tick_now(self) -> int:
        """The control period (tick) the run is in."""
        return int(self._bt_wake_up.period)

    def end_attempt(self, reason: str | None, in_contact: bool = False) -> None:
        """End the grasp attempt going (``bt_grasp.behaviours.attempts``): SUCCEEDED with ``reason`` None, else by
        the reason (a stall ``in_contact`` rules out its neighbourhood); written to the log."""
        self.log_attempt(self.cell.attempts.end(reason, self.bt_path, self.tick_now(), in_contact))

    def log_attempt(self, attempt: Attempt | None) -> None:
        if attempt is not None:
            self.cell.media.attempt(attempt)

    def input_detection(self, port: str) -> Detection | None:
        """A perceived object from a port, or None when the port holds none (or something else)."""
        value = self.ports.get(port)
        return value if isinstance(value, Detection) else None

    def input_detections(self, port: str) -> tuple[Detection, ...]:
        """A list of perceived objects from a port (empty when it holds none)."""
        value = self.ports.get(port)
        if isinstance(value, Detection):
            return (value,)
        if isinstance(value, tuple | list):
            return tuple(v for v in value if isinstance(v, Detection))
        return ()


class HaltCancelsJob:
    """For a robot leaf that runs a motion (``self.job``, a ``MotionJob``): when the tree halts it, the motion is
    cancelled (the arm is brought to rest), not left running. Put it before the leaf's base class."""

    def terminate(self, new_status: Status) -> None:
        job = getattr(self, "job", None)
        if job is not None and new_status == Status.IDLE:
            job.cancel()
