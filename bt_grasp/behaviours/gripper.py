"""OpenGripper, Grasp and IsGrasped: the gripper, judged by its measured finger width only."""

from __future__ import annotations

from bt_grasp.behaviours.base import RobotLeaf
from bt_grasp.behaviours.reasons import FailureReason
from bt_grasp.robot_description import MAX_OPENING_M
from bt_grasp.tree.node_api import Status, action, condition, input_port, output_port

#: the fingers count as closed on nothing below this width (when the width of what they close on is not known)
EMPTY_WIDTH_M = 0.004
#: Grasp's grip force per finger unless the tree sets one, N
GRASP_FORCE_N = 40.0
#: the joints' closed limit is 0: with nothing between the pads they come this close to it
CLOSED_ON_NOTHING_M = 0.001
#: with a planned grasp, a gap at least this wide holds something: the thinnest part the fingers hold (the
#: household L bracket's 4 mm plate closes them to ~3.9 mm), with room for the pads' give
HELD_MIN_M = 0.002


def empty_below_m(expected_width_m: float | None) -> float:
    """The measured finger gap under which a grip holds nothing. Without a planned grasp: ``EMPTY_WIDTH_M``, as
    always. With one (its width seen ``expected_width_m``): ``HELD_MIN_M``, or half the width seen when that is
    less, never under ``CLOSED_ON_NOTHING_M``. A grasp planned from a footprint may close on a thinner part of
    the object than the footprint's width (the L bracket seen 38 mm across, held by its 4 mm plate), so the
    width seen only lowers the bar; only fingers at their closed limit hold nothing."""
    if expected_width_m is None or not expected_width_m > 0.0:
        return EMPTY_WIDTH_M
    return max(CLOSED_ON_NOTHING_M, min(HELD_MIN_M, 0.5 * expected_width_m))


def planned_width_m(grasp: object) -> float | None:
    """The width seen between the pads of a grasp on the blackboard (a GraspPlan or a candidate), else None."""
    width = getattr(grasp, "width_m", None)
    return float(width) if isinstance(width, int | float) and not isinstance(width, bool) else None
#: the width must change less than this per tick to count as settled
SETTLED_M = 2e-5


class _GripperMove(RobotLeaf):
    """Command the fingers, then wait (across ticks) until their width settles or a timeout passes."""

    timeout_s = 1.5

    def command(self) -> None:
        raise NotImplementedError

    def initialise(self) -> None:
        self.command()
        self._t0 = self.now_s()
        self._last = self.cell.robot.gripper_width_m()
        self._still_ticks = 0

    def settled(self) -> bool:
        width = self.cell.robot.gripper_width_m()
        self._still_ticks = self._still_ticks + 1 if abs(width - self._last) < SETTLED_M else 0
        self._last = width
        return self._still_ticks >= 5

    def timed_out(self) -> bool:
        return self.now_s() - self._t0 > self.timeout_s


@action(reasons=(FailureReason.TIMEOUT,), needs_robot=True)
class OpenGripper(_GripperMove):
    """Open the fingers fully."""

    def command(self) -> None:
        self.cell.robot.open_gripper()

    def update(self) -> Status:
        width = self.cell.robot.gripper_width_m()
        self.feedback_message = f"opening: {width * 1e3:.1f} mm"
        if width > MAX_OPENING_M - 0.002:
            return Status.SUCCESS
        if self.timed_out():
            return self.fail(FailureReason.TIMEOUT, f"the gripper opened only to {width * 1e3:.1f} mm")
        return Status.RUNNING


@action(
    ports=[
        input_port("force", float, GRASP_FORCE_N, "grip force per finger, N"),
        output_port("width", object, "measured width once closed, m", default="{grasp_width_m}"),
        input_port("grasp", object, "{grasp}", "the grasp being closed (from PlanGrasp): its width seen says what an "
                   "empty grip is"),
    ],
    reasons=(FailureReason.GRASP_EMPTY, FailureReason.TIMEOUT),
    needs_robot=True,
)
class Grasp(_GripperMove):
    """Close the fingers with a bounded force; FAILURE (GRASP_EMPTY) when they close on nothing: a gap under
    :func:`empty_below_m` of the planned grasp's width (a thin object is held at a gap of a few mm)."""

    def command(self) -> None:
        self.cell.robot.close_gripper(self.ports.require("force", float))

    def update(self) -> Status:
        width = self.cell.robot.gripper_width_m()
        self.feedback_message = f"closing: {width * 1e3:.1f} mm"
        if not (self.settled() or self.timed_out()):
            return Status.RUNNING
        self.ports.set("width", width)
        if width > MAX_OPENING_M - 0.003:
            self.end_attempt(FailureReason.TIMEOUT.value)
            return self.fail(FailureReason.TIMEOUT, f"the fingers did not close (still {width * 1e3:.1f} mm open)")
        empty_below = empty_below_m(planned_width_m(self.ports.get("grasp")))
        if width < empty_below:
            self.end_attempt(FailureReason.GRASP_EMPTY.value)
            return self.fail(FailureReason.GRASP_EMPTY, f"the fingers closed to {width * 1e3:.1f} mm: nothing held")
        self.feedback_message = f"holding an object {width * 1e3:.1f} mm wide"
        return Status.SUCCESS


@condition(reasons=(FailureReason.GRASP_EMPTY, FailureReason.SLIPPED), needs_robot=True)
class IsGrasped(RobotLeaf):
    """SUCCESS while the gripper is commanded closed and its fingers rest on something."""

    def update(self) -> Status:
        robot = self.cell.robot
        width = robot.gripper_width_m()
        if robot.gripper_target_width_m() > 0.0:
            return self.fail(FailureReason.GRASP_EMPTY, "the gripper is open")
        if width < EMPTY_WIDTH_M:
            return self.fail(FailureReason.SLIPPED, f"the fingers are closed ({width * 1e3:.1f} mm): nothing held")
        self.feedback_message = f"holding {width * 1e3:.1f} mm"
        return Status.SUCCESS
