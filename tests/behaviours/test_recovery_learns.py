"""Recovery that learns within a run (issue 46), tick by tick with stand-ins (no simulator).

The shipped recovery tree (``trees/pick_with_recovery.xml``, its LoadCalibration left out: the cell is
calibrated) runs against a robot stand-in that follows its joint targets at once, the real kinematics and
planner, and a camera that returns the perception tests' synthetic RGB-D frames of a red 5 cm box:

- a failed grasp is not repeated: the fingers close on nothing at every attempt (GRASP_EMPTY), and no two of
  the grasps the tree makes are the same attempt (within 5 mm and 10 degrees, a grasp and its twin with the
  closing direction reversed being one);
- a grasp that stalled in contact rules out its neighbours and the next attempt changes family: the arm stops
  on the way down (TRACKING_ERROR in Approach's descent); the next grasp is not from above and lies more than
  15 mm or 20 degrees from the stalled one, and it lifts the box (a 10 cm tall one: a side grasp's wrist clears
  the table).

Each of these fails on the code before issue 46: the tree's recovery sets ``skip := 0`` after both failures, so
PlanGrasp ranked the same candidates again and took the first.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from behaviour_fakes import FakeRobot, fake_cell
from numpy.typing import NDArray
from perception_synth import DEFAULT_T_BASE_CAMERA, Box, render

from bt_grasp.behaviours import robot_registry
from bt_grasp.clock import ManualClock
from bt_grasp.interfaces import Mount, RGBDFrame
from bt_grasp.tree.loader import LoadedTree, load_tree_from_string

REPO = Path(__file__).resolve().parents[2]
HOME = np.array([0.0, -1.9, 1.9, -1.57, -1.57, 0.0])


class Camera:
    mount = Mount.EYE_TO_HAND

    def __init__(self, frame: RGBDFrame) -> None:
        self.frame = frame

    def capture(self) -> RGBDFrame:
        return self.frame


class Calibration:
    mount = "eye-to-hand"
    tool_link = "tool0"

    def T_base_camera_at(self, T_base_tool: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
        return DEFAULT_T_BASE_CAMERA


class StallingRobot(FakeRobot):
    """Follows its joint targets at once, except while ``frozen`` (the arm stopped against something)."""

    frozen = False

    def set_joint_targets(self, q_rad: NDArray[np.float64], qd_rad_s: NDArray[np.float64] | None = None) -> None:
        if not self.frozen:
            super().set_joint_targets(q_rad, qd_rad_s)


def _shipped_pick_with_recovery(robot: FakeRobot, clock: ManualClock, height_m: float = 0.05) -> LoadedTree:
    text = (REPO / "trees" / "pick_with_recovery.xml").read_text()
    text = text.replace('<LoadCalibration file="{calibration_file}"/>', "")  # the cell is calibrated
    tree = load_tree_from_string(text, robot_registry(installed=False), clock=clock)
    cell = fake_cell(robot, clock)
    cell.camera = Camera(render([Box((0.45, 0.0), (0.05, 0.05, height_m))]))
    cell.calibration = Calibration()
    for node in tree.nodes():
        node.setup(cell=cell)
    tree.root_blackboard.set("color", "red")
    tree.root_blackboard.set("lift_height", 0.1)
    return tree


def _gap(T_a: NDArray[np.float64], T_b: NDArray[np.float64]) -> tuple[float, float]:
    """(mm, deg) between two tool poses, a pose and its twin (half a turn about the approach axis) being one."""
    twin = np.diag([-1.0, -1.0, 1.0])
    angles = [math.degrees(math.acos(float(np.clip((np.trace(T_a[:3, :3].T @ R) - 1) / 2, -1, 1))))
              for R in (T_b[:3, :3], T_b[:3, :3] @ twin)]
    return float(np.linalg.norm(T_a[:3, 3] - T_b[:3, 3])) * 1e3, min(angles)


def _run(tree: LoadedTree, robot: StallingRobot, clock: ManualClock, stall_first_descent: bool = False,
         max_ticks: int = 8000) -> tuple[str, list[NDArray[np.float64]], list[str]]:
    """Tick to the end; the tool poses of the grasps Approach started, in order, and the failure reasons."""
    grasps: list[NDArray[np.float64]] = []
    reasons: list[str] = []
    approach = tree.find("Approach")
    stalled = False
    status = "RUNNING"
    for _ in range(max_ticks):
        before = approach.bt_state.value
        status = tree.tick().value
        if approach.bt_state.value == "RUNNING" and before != "RUNNING":
            grasps.append(np.asarray(tree.root_blackboard.get("grasp").T_base_tcp_grasp, dtype=float))
        if stall_first_descent and not stalled and approach.feedback_message == "descend":
            robot.frozen = stalled = True  # the fingers met something on the way down
        if robot.frozen and approach.bt_state.value != "RUNNING":
            robot.frozen = False
        reason = tree.root_blackboard.get("failure_reason", None)
        if reason and (not reasons or reasons[-1] != reason):
            reasons.append(str(reason))
        if status != "RUNNING":
            break
        robot.step()
        clock.advance_s(0.01)
    return status, grasps, reasons


def test_a_failed_grasp_is_not_repeated() -> None:
    # every attempt: Perceive (the box), PlanGrasp, Approach, Grasp -> GRASP_EMPTY (the fingers close on nothing),
    # Recover's regrasp branch (open, retreat, home, skip := 0); the grasps made must all differ
    clock, robot = ManualClock(), StallingRobot(object_width_m=0.0)
    robot.q = HOME.copy()
    tree = _shipped_pick_with_recovery(robot, clock)
    status, grasps, reasons = _run(tree, robot, clock)
    assert status == "FAILURE"
    assert "GRASP_EMPTY" in reasons
    assert len(grasps) >= 2
    for i, a in enumerate(grasps):
        for b in grasps[i + 1:]:
            mm, deg = _gap(a, b)
            assert mm > 5.0 or deg > 10.0, f"a grasp repeated ({mm:.1f} mm, {deg:.1f} deg from an earlier one)"


def test_a_stalled_grasp_excludes_its_neighbours_and_the_next_attempt_changes_family() -> None:
    # attempt 1: a top-down grasp; the arm stops on the way down (TRACKING_ERROR in Approach's descent);
    # Recover's rehome branch (back off, open, home, skip := 0); attempt 2: another family (not from above), more
    # than 15 mm or 20 degrees from the stalled grasp; the box is held (5 cm between the fingers) and lifted.
    # The box stands 10 cm tall: a side grasp's wrist clears the table
    clock, robot = ManualClock(), StallingRobot(object_width_m=0.05)
    robot.q = HOME.copy()
    tree = _shipped_pick_with_recovery(robot, clock, height_m=0.10)
    status, grasps, reasons = _run(tree, robot, clock, stall_first_descent=True)
    assert reasons[0] == "TRACKING_ERROR"
    assert status == "SUCCESS"
    assert len(grasps) == 2
    first, second = grasps
    assert -first[2, 2] > math.cos(math.radians(30))  # the stalled grasp came from above
    assert -second[2, 2] < math.cos(math.radians(30)), "the next attempt is a grasp from above again"
    mm, deg = _gap(first, second)
    assert mm > 15.0 or deg > 20.0


# --- regrasp to place ------------------------------------------------------------------------------------------

#: the held box (base frame): 6 x 4 x 4 cm, lying along x; the place target, and the neighbour beside it
HELD_AT, PLACE_AT = (0.40, 0.15), (0.45, -0.15)


class PadsMeetANeighbour:
    """The real planner, except that at the place target a tool closing along the base y axis (within 30
    degrees) collides: what a neighbour 2 cm beside the target on each side along y does to the open pads.
    Every plan, straight line and configuration check of such a release fails; anything else is the planner's."""

    def __init__(self, planner: object, kinematics: object) -> None:
        self.planner, self.kinematics = planner, kinematics

    @staticmethod
    def blocked(T: NDArray[np.float64]) -> bool:
        near = math.dist(T[:2, 3], PLACE_AT) < 0.05 and T[2, 3] < 0.25
        return near and abs(float(T[1, 1])) > math.cos(math.radians(30))

    def plan_to_pose(self, q_start: NDArray[np.float64], T: NDArray[np.float64], scene: object,
                     options: object = None) -> object:
        from bt_grasp.motion.planner import PlanResult, PlanStatus

        if self.blocked(np.asarray(T)):
            return PlanResult(status=PlanStatus.GOAL_IN_COLLISION, message="the pads meet the neighbour (stand-in)")
        return self.planner.plan_to_pose(q_start, T, scene, options)  # type: ignore[attr-defined]

    def plan_to_joints(self, q_start: NDArray[np.float64], q_goal: NDArray[np.float64], scene: object,
                       options: object = None) -> object:
        from bt_grasp.motion.planner import PlanResult, PlanStatus

        if self.blocked(self.kinematics.fk(q_goal)):  # type: ignore[attr-defined]
            return PlanResult(status=PlanStatus.GOAL_IN_COLLISION, message="the pads meet the neighbour (stand-in)")
        return self.planner.plan_to_joints(q_start, q_goal, scene, options)  # type: ignore[attr-defined]

    def straight_line(self, q_start: NDArray[np.float64], T: NDArray[np.float64], scene: object) -> object:
        from bt_grasp.motion.cartesian import CartesianResult, CartesianStatus

        if self.blocked(np.asarray(T)):
            return CartesianResult(CartesianStatus.COLLISION, message="the pads meet the neighbour (stand-in)")
        return self.planner.straight_line(q_start, T, scene)  # type: ignore[attr-defined]

    def checker(self, scene: object, margin_m: float) -> object:
        real, kin, blocked = self.planner.checker(scene, margin_m), self.kinematics, self.blocked  # type: ignore[attr-defined]

        class Checker:
            def is_valid(self, q: NDArray[np.float64]) -> bool:
                return not blocked(kin.fk(q)) and bool(real.is_valid(q))  # type: ignore[attr-defined]

        return Checker()


class SetDownCamera:
    """Shows the box where SetDown left it (the blackboard's set_down_pose), else where it was picked."""

    mount = Mount.EYE_TO_HAND

    def __init__(self) -> None:
        self.tree: LoadedTree | None = None

    def capture(self) -> RGBDFrame:
        assert self.tree is not None
        pose = self.tree.root_blackboard.get("set_down_pose", None)
        xy, yaw = (HELD_AT, 0.0) if pose is None else ((pose.x_m, pose.y_m), math.radians(pose.yaw_deg or 0.0))
        return render([Box(xy, (0.06, 0.04, 0.04), yaw)])


PLACE_PROBE = """
  <BehaviorTree ID="Probe">
    <SubTree ID="PlaceObject" _autoremap="true"/>
  </BehaviorTree>
</root>"""


def test_a_place_blocked_for_every_yaw_leads_to_a_regrasp() -> None:
    # The box is held across its narrow side (the pads close along base y). Place at PLACE_AT: both of its
    # footprint's turns (0 and 180 deg) keep the pads along y, where they meet the neighbours: PLACE_BLOCKED
    # for every yaw, before the arm moves. RegraspToPlace: SetDown in free space, look, PlanRegrasp keeps only a
    # grip whose placement is reachable (across the long side: the pads along x), grasp, lift; the next
    # attempt places it. On the code before issue 46 Place was tried three times the same way and failed.
    from bt_grasp.behaviours.grasp_plan import GraspPlan
    from bt_grasp.behaviours.pose import Pose
    from bt_grasp.perception.antipodal import rank_grasps
    from bt_grasp.perception.results import Detection

    clock, robot = ManualClock(), StallingRobot(object_width_m=0.04)
    text = (REPO / "trees" / "lib" / "place.xml").read_text()
    text = text.replace('<root BTCPP_format="4">', '<root BTCPP_format="4" main_tree_to_execute="Probe">')
    tree = load_tree_from_string(text.replace("</root>", PLACE_PROBE), robot_registry(installed=False), clock=clock)
    cell = fake_cell(robot, clock)
    cell.planner = PadsMeetANeighbour(cell.planner, cell.kinematics)  # type: ignore[assignment]
    camera = SetDownCamera()
    camera.tree = tree
    cell.camera, cell.calibration = camera, Calibration()
    for node in tree.nodes():
        node.setup(cell=cell)
    held = Detection(label="red", pixel_box=(0, 0, 10, 10), centroid_base_m=(*HELD_AT, 0.02),
                     size_m=(0.06, 0.04, 0.04), yaw_rad=0.0, point_count=500, confidence=1.0)
    narrow = next(c for c in rank_grasps(held).candidates if abs(c.T_base_tcp_grasp[1, 1]) > 0.9)
    # the arm holds it 10 cm up, the fingers closed on it
    T_up = np.array(narrow.T_base_tcp_grasp, dtype=float)
    T_up[2, 3] += 0.10
    robot.q = cell.kinematics.ik(T_up, HOME).q
    robot.close_gripper()
    for _ in range(20):
        robot.step()
    grasp = GraspPlan(narrow, robot.q.copy(), np.stack([robot.q, robot.q]), held, (held,))
    for key, value in (("grasp", grasp), ("target", held), ("objects", (held,)), ("lift_height", 0.1),
                       ("place_pose", Pose(*PLACE_AT))):
        tree.root_blackboard.set(key, value)
    statuses: dict[str, list[str]] = {"SetDown": [], "PlanRegrasp": []}
    status = "RUNNING"
    present = {n.name for n in tree.nodes()}
    for _ in range(8000):
        before = {name: tree.find(name).bt_state.value for name in statuses if name in present}
        status = tree.tick().value
        for name in before:
            now = tree.find(name).bt_state.value
            if now in ("SUCCESS", "FAILURE") and now != before[name]:
                statuses[name].append(now)
        if status != "RUNNING":
            break
        robot.step()
        clock.advance_s(0.01)
    assert status == "SUCCESS", statuses
    assert statuses == {"SetDown": ["SUCCESS"], "PlanRegrasp": ["SUCCESS"]}
    regrasp = tree.root_blackboard.get("grasp")
    assert abs(float(regrasp.T_base_tcp_grasp[1, 1])) < math.cos(math.radians(30))  # the new grip: pads not along y
    # the run's attempts: the place blocked for both turns, the set-down, the regrasp, the place that worked
    made = [(a.kind.value, a.leaf.rsplit("/", 1)[-1].split("::")[0], a.outcome.value) for a in cell.attempts.attempts]
    assert made == [("place", "Place", "BLOCKED"), ("place", "SetDown", "SUCCEEDED"),
                    ("grasp", "PlanRegrasp", "SUCCEEDED"), ("place", "Place", "SUCCEEDED")], made
    first = cell.attempts.attempts[0]
    assert first.every_turn_blocked and len(first.blocked) == 2


# --- a rolled-away object is looked for again ------------------------------------------------------------------

class RollingCamera:
    """The box where it stands until it rolls away (``rolled``), then where it came to rest."""

    mount = Mount.EYE_TO_HAND

    def __init__(self, before: Box, after: Box) -> None:
        self.frames = (render([before]), render([after]))
        self.rolled = False

    def capture(self) -> RGBDFrame:
        return self.frames[int(self.rolled)]


def test_a_rolled_away_object_is_looked_for_again(tmp_path: Path) -> None:
    # The shipped pick by class (trees/pick_class.xml) with a tiny stand-in model that names the box where it
    # first stood, whatever the picture. Attempt 1: the grasp closes on nothing (GRASP_EMPTY) and the box rolls
    # 16 cm away, where the model names nothing. Attempt 2: no box named (SelectObject NO_DETECTION): the tree
    # looks again from home at the whole workspace and finds the box the failed grasp was on by what was seen of
    # it (FindLost: its size and colour), grasps it there and lifts it. On the code before issue 46 every later
    # attempt ended NO_DETECTION.
    from detector.synthetic_boxes import image_box, model_seeing

    before, after = Box((0.45, 0.0), (0.05, 0.05, 0.05)), Box((0.52, 0.15), (0.05, 0.05, 0.05))
    model = model_seeing(tmp_path / "m.onnx", [image_box(before, "box", 0.9, class_id=0)], {0: "box", 1: "mug"})
    text = (REPO / "trees" / "pick_class.xml").read_text()
    text = text.replace('<LoadCalibration file="{calibration_file}"/>', "")  # the cell is calibrated
    text = text.replace('detector="learned"', f'detector="learned" model="{model}"')
    clock, robot = ManualClock(), StallingRobot(object_width_m=0.0)
    robot.q = HOME.copy()
    tree = load_tree_from_string(text, robot_registry(installed=False), clock=clock)
    cell = fake_cell(robot, clock)
    camera = RollingCamera(before, after)
    cell.camera, cell.calibration = camera, Calibration()
    for node in tree.nodes():
        node.setup(cell=cell)
    tree.root_blackboard.set("class", "box")
    tree.root_blackboard.set("lift_height", 0.1)
    grasp = tree.find("Grasp")
    starts: list[NDArray[np.float64]] = []
    approach = tree.find("Approach")
    status = "RUNNING"
    for _ in range(8000):
        before_state = approach.bt_state.value
        status = tree.tick().value
        if approach.bt_state.value == "RUNNING" and before_state != "RUNNING":
            starts.append(np.asarray(tree.root_blackboard.get("grasp").T_base_tcp_grasp, dtype=float))
        if not camera.rolled and tree.root_blackboard.get("failure_reason", None) == "GRASP_EMPTY":
            camera.rolled = True  # the fingers pushed it: it rolled away and came to rest 16 cm on
            robot.object_width_m = 0.05
        if status != "RUNNING":
            break
        robot.step()
        clock.advance_s(0.01)
    assert camera.rolled and grasp is not None
    assert status == "SUCCESS"
    assert len(starts) == 2
    assert math.dist(starts[1][:2, 3], after.centre_xy) < 0.02  # grasped where it rolled to
