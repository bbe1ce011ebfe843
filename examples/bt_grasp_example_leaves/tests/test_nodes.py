"""The example plugin's own tests: its leaves tick by tick against a stand-in robot, no simulator."""

from __future__ import annotations

from bt_grasp_example_leaves.nodes import register

from bt_grasp.behaviours.cell import make_cell
from bt_grasp.clock import ManualClock
from bt_grasp.scene.format import Scene
from bt_grasp.tree import builtin_registry, load_tree_from_string


class StandInRobot:
    """Only what GripperOpenAtLeast reads: the fingers' opening."""

    def __init__(self, width_m: float) -> None:
        self.width_m = width_m

    def gripper_width_m(self) -> float:
        return self.width_m


class NoCamera:
    def capture(self) -> None:
        return None


TREE = """<root BTCPP_format="4"><BehaviorTree ID="Main">
  <Sequence>
    <Fallback>
      <GripperOpenAtLeast min_mm="40"/>
      <Sequence><FailureIs reason="GRIPPER_TOO_NARROW"/><Script code="note := 'narrow'"/></Sequence>
    </Fallback>
    <Dwell seconds="0.02"/>
  </Sequence>
</BehaviorTree></root>"""


def _run(width_m: float) -> tuple[list[str], dict[str, object]]:
    registry = builtin_registry()
    register(registry)
    clock = ManualClock()
    tree = load_tree_from_string(TREE, registry, clock=clock)
    cell = make_cell(StandInRobot(width_m), NoCamera(), clock, Scene(), seed=0)  # type: ignore[arg-type]
    for node in tree.nodes():
        node.setup(cell=cell)
    statuses = []
    for _ in range(3):
        statuses.append(tree.tick().value)
        clock.advance_s(0.010)
    return statuses, tree.root_blackboard.items()


def test_open_gripper_passes_and_dwell_waits_in_simulated_time() -> None:
    # t=0: 85 mm >= 40 mm: SUCCESS; Dwell starts (deadline t=20 ms): RUNNING; t=10: RUNNING; t=20: SUCCESS
    statuses, bb = _run(0.085)
    assert statuses == ["RUNNING", "RUNNING", "SUCCESS"]
    assert "failure_reason" not in bb and "note" not in bb


def test_narrow_gripper_fails_with_the_plugins_reason() -> None:
    statuses, bb = _run(0.010)
    assert statuses == ["RUNNING", "RUNNING", "SUCCESS"]  # the Fallback recovers through FailureIs
    assert bb["note"] == "narrow"  # FailureIs matched GRIPPER_TOO_NARROW
    assert "failure_reason" not in bb  # the tree succeeded: the recovered failure is cleared
