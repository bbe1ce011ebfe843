"""Stand-ins for the cell, world and tree that the injectors wrap (no simulator, no planner)."""

from __future__ import annotations

from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bt_grasp.clock import ManualClock
from bt_grasp.interfaces import CameraIntrinsics, RGBDFrame
from bt_grasp.motion.cartesian import CartesianResult, CartesianStatus
from bt_grasp.motion.kinematics import IKResult, IKStatus
from bt_grasp.motion.planner import PlanResult, PlanStatus
from bt_grasp.tree.node import BtStatus

INTRINSICS = CameraIntrinsics(64, 48, 50.0, 50.0, 31.5, 23.5)


class FakeCamera:
    def __init__(self, clock: ManualClock) -> None:
        self.clock = clock
        self.captures = 0

    @property
    def intrinsics(self) -> CameraIntrinsics:
        return INTRINSICS

    @property
    def mount(self) -> str:
        return "eye-to-hand"

    def capture(self) -> RGBDFrame | None:
        self.captures += 1
        depth = np.full((48, 64), 0.8, dtype=np.float32)
        depth[:, :4] = 0.0  # a strip with no depth
        color = np.zeros((48, 64, 3), dtype=np.uint8)
        return RGBDFrame(color, depth, INTRINSICS, self.clock.now_ns(), "eye-to-hand")


class FakeRobot:
    def __init__(self) -> None:
        self.targets: list[NDArray[np.float64]] = []
        self.gripper: list[str] = []

    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(f"j{i}" for i in range(6))

    def joint_positions(self) -> NDArray[np.float64]:
        return np.zeros(6)

    def joint_velocities(self) -> NDArray[np.float64]:
        return np.zeros(6)

    def set_joint_targets(self, q_rad: NDArray[np.float64], qd_rad_s: NDArray[np.float64] | None = None) -> None:
        self.targets.append(np.asarray(q_rad))

    def open_gripper(self) -> None:
        self.gripper.append("open")

    def close_gripper(self, force_n: float | None = None) -> None:
        self.gripper.append(f"close {force_n}")

    def gripper_width_m(self) -> float:
        return 0.05

    def gripper_target_width_m(self) -> float:
        return 0.0


class FakePlanner:
    def __init__(self) -> None:
        self.calls = 0

    def plan_to_pose(self, q: Any, T: Any, scene: Any, options: Any) -> PlanResult:
        self.calls += 1
        return PlanResult(PlanStatus.OK, path=np.zeros((2, 6)))

    def plan_to_joints(self, q: Any, q_goal: Any, scene: Any, options: Any) -> PlanResult:
        self.calls += 1
        return PlanResult(PlanStatus.OK, path=np.zeros((2, 6)))

    def checker(self, scene: Any, margin_m: float) -> str:
        return "checker"

    def straight_line(self, q: Any, T: Any, scene: Any) -> CartesianResult:
        return CartesianResult(CartesianStatus.OK, path=np.zeros((2, 6)), fraction=1.0)


class FakeKinematics:
    def ik(self, T: Any, q: NDArray[np.float64], **kwargs: Any) -> IKResult:
        return IKResult(IKStatus.OK, np.ones(6), 0.0, 0.0, 3)

    def ik_solutions(self, T: Any, q: NDArray[np.float64], **kwargs: Any) -> tuple[list[Any], IKResult]:
        return [np.ones(6)], self.ik(T, q)

    def fk(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.eye(4)


@dataclass
class FakeCalibration:
    T_base_camera: NDArray[np.float64]
    mount: str = "eye-to-hand"
    tool_link: str = "tool0"

    def T_base_camera_at(self, T_base_tool: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
        return self.T_base_camera


@dataclass
class FakeCell:
    camera: Any
    robot: Any
    clock: ManualClock
    planner: Any
    kinematics: Any
    calibration: Any = None


class FakeNode:
    """A leaf as the injector sees it: name, type, path, kind, state and an ``initialise`` to wrap."""

    def __init__(self, name: str, kind: str = "Action") -> None:
        self.name = name
        self.bt_type = name
        self.bt_path = f"Main/{name}"
        self.bt_kind = SimpleNamespace(value=kind)
        self.bt_state = BtStatus.IDLE
        self.bt_pre_tick: Any = None
        self.initialised = 0

    def initialise(self) -> None:
        self.initialised += 1

    def enter(self) -> None:
        """What a tick does to a leaf that was not RUNNING: the pre-tick hook, ``initialise`` (then ``update``)."""
        if self.bt_pre_tick is not None:
            self.bt_pre_tick(self)
        self.initialise()


class FakePhysics:
    """The simulator's physics hook as a record: pad friction, finger force limit, object velocities."""

    def __init__(self) -> None:
        self.colors = {"red_box": "red", "blue_box": "blue"}
        self.friction = {"red_box": 0.8, "blue_box": 0.4}
        self.table_friction = 0.6
        self.pad_friction = 1.0
        self.force_limit_n = 40.0
        self.velocities: dict[str, tuple[float, float, float]] = {}
        self.touching: set[str] = set()  # what the fingers touch now

    def object_names(self) -> tuple[str, ...]:
        return tuple(self.colors)

    def object_color(self, name: str) -> str | None:
        return self.colors.get(name)

    def sliding_friction(self, name: str) -> float:
        return 0.5 * (self.friction[name] + self.table_friction)

    def set_velocity(self, name: str, velocity_m_s: tuple[float, float, float]) -> None:
        self.velocities[name] = velocity_m_s

    def objects_touching_fingers(self) -> frozenset[str]:
        return frozenset(self.touching)

    def weaken_grip(self, friction: float | None, force_n: float | None) -> tuple[dict[str, float], Any]:
        details: dict[str, float] = {}
        old = self.pad_friction
        if friction is not None:
            details["pad_friction_before"] = old
            self.pad_friction = friction
        if force_n is not None:
            details["force_limit_before_n"] = self.force_limit_n
            self.force_limit_n = force_n

        def restore() -> None:
            self.pad_friction = old

        return details, restore


class FakeTree:
    def __init__(self, nodes: list[FakeNode], color: str | None = None) -> None:
        self._nodes = nodes
        values = {"color": color} if color else {}
        self.root_blackboard = SimpleNamespace(has=values.__contains__, get=values.get)

    def nodes(self) -> list[FakeNode]:
        return self._nodes


@dataclass
class FakeRecorder:
    faults: list[tuple[int, int, dict[str, Any]]] = field(default_factory=list)

    def write_fault(self, stamp_ns: int, tick: int, fault: dict[str, Any]) -> None:
        self.faults.append((stamp_ns, tick, fault))


@dataclass
class Rig:
    """A prepared run made of fakes (what ``install_faults`` needs), plus handles on the originals."""

    cell: FakeCell
    physics: FakePhysics
    fault_seed_sequence: np.random.SeedSequence
    tree: FakeTree
    camera: FakeCamera
    robot: FakeRobot
    planner: FakePlanner
    kinematics: FakeKinematics
    clock: ManualClock
    nodes: dict[str, FakeNode]


def rig(leaves: tuple[str, ...] = ("Perceive", "PlanGrasp", "Approach", "Grasp", "Lift"), seed: int = 0,
        color: str | None = "red") -> Rig:
    clock = ManualClock()
    camera, robot, planner, kin = FakeCamera(clock), FakeRobot(), FakePlanner(), FakeKinematics()
    cell = FakeCell(camera, robot, clock, planner, kin)
    nodes = {n: FakeNode(n) for n in leaves}
    control = FakeNode("pick", kind="Control")
    tree = FakeTree([control, *nodes.values()], color)
    fault_seeds = np.random.SeedSequence(seed).spawn(3)[2]
    return Rig(cell, FakePhysics(), fault_seeds, tree, camera, robot, planner, kin, clock, nodes)
