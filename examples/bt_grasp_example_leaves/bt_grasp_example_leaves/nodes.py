"""The example plugin's nodes, written only against :mod:`bt_grasp.nodes`."""

from __future__ import annotations

from bt_grasp.nodes import Deadline, Leaf, NodeRegistry, Reason, RobotLeaf, Status, action, condition, input_port

#: the example's own failure reason: a tree tests it with <FailureIs reason="GRIPPER_TOO_NARROW"/>
GRIPPER_TOO_NARROW = Reason("GRIPPER_TOO_NARROW", "The gripper is open less than the leaf asked for.")


@condition(ports=[input_port("min_mm", float, 50.0, "the least opening between the fingers, in millimetres")],
           needs_robot=True)
class GripperOpenAtLeast(RobotLeaf):
    """SUCCESS when the fingers are at least min_mm apart, else FAILURE with GRIPPER_TOO_NARROW."""

    def update(self) -> Status:
        width_mm = self.cell.robot.gripper_width_m() * 1000.0
        wanted_mm = self.input_float("min_mm")
        if width_mm < wanted_mm:
            return self.failed(GRIPPER_TOO_NARROW, f"the gripper is open {width_mm:.1f} mm, less than {wanted_mm:g} mm")
        return Status.SUCCESS


@action(ports=[input_port("seconds", float, 0.5, "how long to wait, in simulated seconds")])
class Dwell(Leaf):
    """RUNNING for the given simulated time, then SUCCESS (the arm holds still meanwhile)."""

    def initialise(self) -> None:
        self.deadline = Deadline.after(self.clock, float(self.ports.get("seconds")))

    def update(self) -> Status:
        return Status.SUCCESS if self.deadline.passed() else Status.RUNNING


def register(registry: NodeRegistry) -> None:
    """The plugin's hook (BT.CPP's BT_REGISTER_NODES): its reason first, then its nodes."""
    registry.register_reason(GRIPPER_TOO_NARROW)
    registry.register(GripperOpenAtLeast.bt_spec)
    registry.register(Dwell.bt_spec)
