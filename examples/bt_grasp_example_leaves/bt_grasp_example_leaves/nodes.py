"""The example plugin's nodes, written only against :mod:`bt_grasp.nodes`, the way bt_grasp writes its own."""

from __future__ import annotations

from bt_grasp.nodes import Deadline, Leaf, NodeRegistry, Reason, RobotLeaf, Status, action, condition, input_port

#: the example's own failure reason: a tree tests it with <FailureIs reason="GRIPPER_TOO_NARROW"/>
GRIPPER_TOO_NARROW = Reason("GRIPPER_TOO_NARROW", "The gripper is open less than the leaf asked for.")


@condition(ports=[input_port("min_mm", float, 50.0, "the least opening between the fingers, in millimetres")],
           needs_robot=True, reasons=[GRIPPER_TOO_NARROW])
class GripperOpenAtLeast(RobotLeaf):
    """SUCCESS when the fingers are at least min_mm apart, else FAILURE with GRIPPER_TOO_NARROW."""

    def update(self) -> Status:
        width_mm = self.cell.robot.gripper_width_m() * 1000.0
        wanted_mm = self.ports.require("min_mm", float)
        if width_mm < wanted_mm:
            return self.fail(GRIPPER_TOO_NARROW, f"the gripper is open {width_mm:.1f} mm, less than {wanted_mm:g} mm")
        return Status.SUCCESS


@action(ports=[input_port("seconds", float, 0.5, "how long to wait, in simulated seconds")])
class Dwell(Leaf):
    """RUNNING for the given simulated time, then SUCCESS (the arm holds still meanwhile)."""

    def initialise(self) -> None:
        self.deadline = Deadline.after(self.clock, self.ports.require("seconds", float))

    def update(self) -> Status:
        return Status.SUCCESS if self.deadline.passed() else Status.RUNNING


def register(registry: NodeRegistry) -> None:
    """The plugin's hook (BT.CPP's BT_REGISTER_NODES): each node registered as BT.CPP's registerNodeType<T> does;
    GRIPPER_TOO_NARROW comes with GripperOpenAtLeast's declaration."""
    registry.register(GripperOpenAtLeast)
    registry.register(Dwell)
