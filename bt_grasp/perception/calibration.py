"""Hand-eye calibration procedure: plan diverse board views, visit them, detect the board, solve.

The robot side is injected: ``kinematics`` (``fk``, ``fk_link``, ``ik``; :class:`bt_grasp.motion.kinematics.
ArmKinematics` fits), ``move_to(q) -> bool`` (plan/execute until the arm is still; False when it could not
get there), ``capture() -> RGBDFrame | None`` and ``joint_positions() -> q`` (measured, read at capture).

View planning uses only installation data: the camera's nominal pose (eye-to-hand: in the base frame;
eye-in-hand: in the tool frame) and where the board nominally is (eye-to-hand: on the tool; eye-in-hand:
on the table). The calibration measures the true transform from the images.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Annotated, Protocol

import numpy as np
from numpy.typing import NDArray
from pydantic import Field
from scipy.spatial.transform import Rotation

from bt_grasp.files.config import StrictModel
from bt_grasp.geometry import Mat4, T_from_xyz_rpy, inv, make_T, rotation_angle_rad, transform_points
from bt_grasp.interfaces import CameraIntrinsics, RGBDFrame
from bt_grasp.perception.calibration_file import CalibrationFile, make_calibration
from bt_grasp.perception.charuco import BoardSpec, corner_object_points, detect_board
from bt_grasp.perception.handeye import EYE_TO_HAND, HandEyeSolution, View, solve_hand_eye
from bt_grasp.scene.format import Scene

log = logging.getLogger(__name__)

Vec = NDArray[np.float64]
Range = tuple[float, float]


class IKLike(Protocol):
    @property
    def ok(self) -> bool: ...

    @property
    def q(self) -> Vec: ...


class Kinematics(Protocol):
    def fk(self, q: Vec) -> Mat4: ...

    def fk_link(self, q: Vec, link: str) -> Mat4: ...

    def ik(self, T_base_tcp_goal: Mat4, q_current: Vec) -> IKLike: ...


class CalibrationSettings(StrictModel):
    """How views are planned and accepted (metres, degrees)."""

    board: BoardSpec = BoardSpec()
    poses: Annotated[int, Field(ge=4, le=60)] = 20  # views to collect
    spare_poses: Annotated[int, Field(ge=0, le=30)] = 4  # extra planned poses used when views are rejected
    tool_link: str = "tool0"  # the frame whose pose is recorded with each view
    min_corners: Annotated[int, Field(ge=4)] = 12  # fewer detected corners: view rejected
    max_reprojection_px: Annotated[float, Field(gt=0)] = 1.0  # worse PnP fit: view rejected
    eye_to_hand_region_m: tuple[Range, Range, Range] = ((0.35, 0.60), (-0.20, 0.20), (0.25, 0.50))
    eye_in_hand_distance_m: Range = (0.35, 0.55)  # camera to board centre
    tilt_deg: Range = (8.0, 35.0)  # board normal away from the line of sight
    roll_deg: Annotated[float, Field(ge=0, le=180)] = 70.0  # random roll about the line of sight, +-
    max_view_angle_deg: Annotated[float, Field(gt=0, lt=90)] = 50.0
    image_margin_px: Annotated[int, Field(ge=0)] = 15
    min_link_height_m: float = 0.05  # collision heuristic: arm links stay above the table top by this
    candidates_per_pose: Annotated[int, Field(ge=1)] = 12
    max_joint_change_rad: Annotated[float, Field(gt=0)] = 1.8  # no joint further than this from the central view


@dataclass(frozen=True)
class BoardMount:
    """A calibration board mounted in the cell (installation data, not ground truth): its spec and nominal
    pose, ``T_tool_board`` (eye-to-hand: on the gripper) or ``T_base_board`` (eye-in-hand: on the table)."""

    spec: BoardSpec
    T_nominal_board: Mat4


@dataclass(frozen=True)
class ViewPlan:
    """What the planner knows: nominal camera and board poses (installation data, not ground truth)."""

    mount: str
    T_nominal_camera: Mat4  # T_base_camera (eye-to-hand) or T_tool_camera (eye-in-hand)
    T_nominal_board: Mat4  # T_tool_board (eye-to-hand) or T_base_board (eye-in-hand)
    intrinsics: CameraIntrinsics


@dataclass(frozen=True)
class CalibrationRun:
    solution: HandEyeSolution
    calibration: CalibrationFile
    views: tuple[View, ...]
    visited: int
    rejected: dict[str, int] = field(default_factory=dict)


def look_at(position: Vec, target: Vec, roll_rad: float = 0.0) -> Mat4:
    """An OpenCV optical frame at ``position`` looking at ``target``, image down towards base -z."""
    z = np.asarray(target, float) - np.asarray(position, float)
    z /= np.linalg.norm(z)
    x = np.cross([0.0, 0.0, -1.0], z)
    x = x / np.linalg.norm(x) if np.linalg.norm(x) > 1e-6 else np.array([0.0, -1.0, 0.0])
    R = np.stack([x, np.cross(z, x), z], axis=1)
    return make_T(R @ Rotation.from_euler("z", roll_rad).as_matrix(), position)


def nominal_plan(scene: Scene, mount: str, intrinsics: CameraIntrinsics, T_nominal_board: Mat4) -> ViewPlan:
    """The camera's nominal pose from the scene file's mount description, in the base (or tool) frame."""
    if mount == EYE_TO_HAND:
        e2h = scene.camera.eye_to_hand
        T_world_cam = look_at(np.array(e2h.position_m), np.array(e2h.look_at_m), np.deg2rad(e2h.roll_deg))
        return ViewPlan(mount, inv(scene.T_world_base()) @ T_world_cam, T_nominal_board, intrinsics)
    eih = scene.camera.eye_in_hand
    return ViewPlan(mount, T_from_xyz_rpy(np.array(eih.xyz_m), np.deg2rad(eih.rpy_deg)), T_nominal_board,
                    intrinsics)


def board_outline(spec: BoardSpec) -> Vec:
    w, h = spec.size_m
    return np.array([[0, 0, 0], [w, 0, 0], [w, h, 0], [0, h, 0]], dtype=float)


def _random_tilt(direction: Vec, rng: np.random.Generator, tilt_rad: float) -> Vec:
    """``direction`` turned by ``tilt_rad`` about a random axis perpendicular to it."""
    a = np.cross(direction, rng.normal(size=3))
    a /= np.linalg.norm(a)
    return np.asarray(Rotation.from_rotvec(a * tilt_rad).apply(direction), dtype=np.float64)


def _frame_with_z(z: Vec, reference_x: Vec, roll_rad: float) -> NDArray[np.float64]:
    x = reference_x - (reference_x @ z) * z
    x /= np.linalg.norm(x)
    R = np.stack([x, np.cross(z, x), z], axis=1)
    return np.asarray(R @ Rotation.from_euler("z", roll_rad).as_matrix(), dtype=np.float64)


def _sample_eye_to_hand(plan: ViewPlan, s: CalibrationSettings, rng: np.random.Generator) -> tuple[Mat4, Mat4]:
    """(T_base_tool, T_base_board) for one random view of the tool-mounted board."""
    (x0, x1), (y0, y1), (z0, z1) = s.eye_to_hand_region_m
    centre = rng.uniform([x0, y0, z0], [x1, y1, z1])
    cam = plan.T_nominal_camera[:3, 3]
    to_cam = (cam - centre) / np.linalg.norm(cam - centre)
    facing = _random_tilt(to_cam, rng, np.deg2rad(rng.uniform(*s.tilt_deg)))
    roll = np.deg2rad(rng.uniform(-s.roll_deg, s.roll_deg))
    R = _frame_with_z(-facing, plan.T_nominal_camera[:3, 0], roll)  # board z points away from its face
    w, h = s.board.size_m
    T_base_board = make_T(R, centre - R @ np.array([w / 2, h / 2, 0.0]))
    return T_base_board @ inv(plan.T_nominal_board), T_base_board


def _sample_eye_in_hand(plan: ViewPlan, s: CalibrationSettings, rng: np.random.Generator) -> tuple[Mat4, Mat4]:
    """(T_base_tool, T_base_board) for one random look at the table-mounted board."""
    w, h = s.board.size_m
    board_centre = transform_points(plan.T_nominal_board, np.array([[w / 2, h / 2, 0.0]]))[0]
    up = -plan.T_nominal_board[:3, 2]  # the printed side faces away from board z
    direction = _random_tilt(up, rng, np.deg2rad(rng.uniform(0.0, s.tilt_deg[1])))
    cam = board_centre + direction * rng.uniform(*s.eye_in_hand_distance_m)
    aim = board_centre + rng.normal(0.0, 0.02, 3)
    z = (aim - cam) / np.linalg.norm(aim - cam)
    roll = np.deg2rad(rng.uniform(-s.roll_deg, s.roll_deg))
    T_base_cam = make_T(_frame_with_z(z, np.array([0.0, -1.0, 0.0]), roll), cam)
    return T_base_cam @ inv(plan.T_nominal_camera), plan.T_nominal_board


def _visible(plan: ViewPlan, T_base_tool: Mat4, T_base_board: Mat4, s: CalibrationSettings) -> bool:
    T_base_cam = plan.T_nominal_camera if plan.mount == EYE_TO_HAND else T_base_tool @ plan.T_nominal_camera
    T_cam_board = inv(T_base_cam) @ T_base_board
    pts = transform_points(T_cam_board, board_outline(s.board))
    if np.any(pts[:, 2] < 0.25):
        return False
    intr, m = plan.intrinsics, s.image_margin_px
    u = intr.fx_px * pts[:, 0] / pts[:, 2] + intr.cx_px
    v = intr.fy_px * pts[:, 1] / pts[:, 2] + intr.cy_px
    if np.any((u < m) | (u > intr.width_px - 1 - m) | (v < m) | (v > intr.height_px - 1 - m)):
        return False
    # the camera must look at the printed side (board -z faces the camera) at a moderate angle
    to_cam = -T_cam_board[:3, 3] / np.linalg.norm(T_cam_board[:3, 3])
    cos_angle = float(-T_cam_board[:3, 2] @ to_cam)
    return bool(cos_angle > np.cos(np.deg2rad(s.max_view_angle_deg)))


def _links_above_table(kin: Kinematics, q: Vec, s: CalibrationSettings, table_z: float) -> bool:
    for link in ("forearm_link", "wrist_1_link", "wrist_2_link", "wrist_3_link", s.tool_link):
        if kin.fk_link(q, link)[2, 3] < table_z + s.min_link_height_m:
            return False
    return True


def plan_calibration_poses(
    plan: ViewPlan, kinematics: Kinematics, q_start: Vec, settings: CalibrationSettings,
    rng: np.random.Generator, *, table_z_base_m: float = 0.0,
    collision_free: Callable[[Vec], bool] | None = None,
) -> list[Vec]:
    """``poses + spare_poses`` reachable, collision-free joint configurations that show the board, chosen
    for diversity (greedy farthest point on board orientation and position) and ordered as a short tour."""
    s = settings
    q_start = np.asarray(q_start, dtype=float)
    T_tool_tcp = inv(kinematics.fk_link(q_start, s.tool_link)) @ kinematics.fk(q_start)
    wanted = s.poses + s.spare_poses
    pool: list[tuple[Vec, Mat4]] = []
    sampler = _sample_eye_to_hand if plan.mount == EYE_TO_HAND else _sample_eye_in_hand
    q_ref = _central_configuration(plan, kinematics, q_start, T_tool_tcp, s)
    for _ in range(wanted * s.candidates_per_pose * 4):
        if len(pool) >= wanted * s.candidates_per_pose:
            break
        T_base_tool, T_base_board = sampler(plan, s, rng)
        if not _visible(plan, T_base_tool, T_base_board, s):
            continue
        result = kinematics.ik(T_base_tool @ T_tool_tcp, q_ref)
        if not result.ok:
            continue
        q = np.asarray(result.q, dtype=float)
        if float(np.max(np.abs(q - q_ref))) > s.max_joint_change_rad:
            continue
        if not _links_above_table(kinematics, q, s, table_z_base_m):
            continue
        if collision_free is not None and not collision_free(q):
            continue
        pool.append((q, T_base_tool if plan.mount == EYE_TO_HAND else T_base_tool @ plan.T_nominal_camera))
    if len(pool) < s.poses:
        raise ValueError(f"only {len(pool)} reachable views of the board found; need {s.poses}")
    chosen = _diverse(pool, wanted)
    return _tour(chosen, q_start)


def _central_configuration(plan: ViewPlan, kinematics: Kinematics, q_start: Vec, T_tool_tcp: Mat4,
                           s: CalibrationSettings) -> Vec:
    """IK of an untilted view in the middle of the sampled region: all views stay near it (one IK branch, no
    wrist flips between consecutive views)."""
    quiet = s.model_copy(update={"tilt_deg": (0.0, 0.0), "roll_deg": 0.0})
    rng = np.random.default_rng(0)
    if plan.mount == EYE_TO_HAND:
        region = np.array(s.eye_to_hand_region_m)
        quiet = quiet.model_copy(update={"eye_to_hand_region_m": tuple((c, c) for c in region.mean(axis=1))})
        T_base_tool, _ = _sample_eye_to_hand(plan, quiet, rng)
    else:
        mid = float(np.mean(s.eye_in_hand_distance_m))
        quiet = quiet.model_copy(update={"eye_in_hand_distance_m": (mid, mid)})
        T_base_tool, _ = _sample_eye_in_hand(plan, quiet, rng)
    result = kinematics.ik(T_base_tool @ T_tool_tcp, q_start)
    if not result.ok:
        raise ValueError("the central calibration view is out of reach; move the board region or the camera")
    return np.asarray(result.q, dtype=float)


def _diverse(pool: list[tuple[Vec, Mat4]], n: int) -> list[Vec]:
    """Greedy farthest-point selection; distance = rotation angle (deg) + 100 * translation (m)."""
    def dist(a: Mat4, b: Mat4) -> float:
        return float(np.degrees(rotation_angle_rad(a[:3, :3], b[:3, :3])) + 100 * np.linalg.norm(a[:3, 3] - b[:3, 3]))

    picked = [0]
    best = np.array([dist(pool[0][1], T) for _, T in pool])
    while len(picked) < min(n, len(pool)):
        k = int(np.argmax(best))
        picked.append(k)
        best = np.minimum(best, [dist(pool[k][1], T) for _, T in pool])
    return [pool[k][0] for k in picked]


def _tour(qs: list[Vec], q_start: Vec) -> list[Vec]:
    left, out, current = list(qs), [], q_start
    while left:
        k = int(np.argmin([np.max(np.abs(q - current)) for q in left]))
        current = left.pop(k)
        out.append(current)
    return out


class ViewCollector:
    """The image side of one hand-eye calibration: judges each capture, keeps the usable views, solves.

    The robot side (moving to each planned pose, waiting until the arm is still, one control period per
    tick) is ``bt_grasp.behaviours.calibration_job.CalibrationJob``: the one procedure both the
    ``Calibrate`` leaf and ``bt-grasp calibrate`` run.
    """

    def __init__(self, plan: ViewPlan, settings: CalibrationSettings) -> None:
        self.plan = plan
        self.settings = settings
        self.views: list[View] = []
        self.visited = 0
        self.rejected = {"unreached": 0, "no_frame": 0, "few_corners": 0, "reprojection": 0}
        self.intrinsics = plan.intrinsics
        self._object_points = corner_object_points(settings.board)

    @property
    def enough(self) -> bool:
        return len(self.views) >= self.settings.poses

    def unreached(self) -> str:
        """A planned pose could not be reached; returns what to report."""
        self.visited += 1
        self.rejected["unreached"] += 1
        return "could not reach the pose"

    def add(self, frame: RGBDFrame | None, T_base_tool: Mat4) -> str:
        """Judge the capture taken at a reached pose (``T_base_tool`` by FK of the measured joints at capture
        time); keeps it when the board is seen well enough. Returns what to report."""
        s = self.settings
        self.visited += 1
        if frame is None:
            self.rejected["no_frame"] += 1
            return "no frame"
        self.intrinsics = frame.intrinsics
        obs = detect_board(frame.color, frame.intrinsics, s.board, s.min_corners)
        if obs.T_camera_board is None:
            self.rejected["few_corners"] += 1
            return f"{obs.n_corners} corners: rejected"
        if obs.reprojection_px > s.max_reprojection_px:
            self.rejected["reprojection"] += 1
            return f"reprojection {obs.reprojection_px:.2f} px: rejected"
        self.views.append(View(np.asarray(T_base_tool, dtype=float), obs.T_camera_board, obs.corner_ids,
                               obs.corners_px, self._object_points[obs.corner_ids]))
        return f"{obs.n_corners} corners, {obs.reprojection_px:.2f} px"

    def solve(self) -> CalibrationRun:
        """Solve every hand-eye method and keep the most consistent; ValueError with fewer than 3 views."""
        s, plan = self.settings, self.plan
        if len(self.views) < 3:
            raise ValueError(f"only {len(self.views)} usable views of the board out of {self.visited} visited "
                             f"({self.rejected}); cannot calibrate")
        solution = solve_hand_eye(plan.mount, self.views, self.intrinsics, board_outline(s.board))
        parent = "base_link" if plan.mount == EYE_TO_HAND else s.tool_link
        calibration = make_calibration(
            plan.mount, solution.X, parent, solution.method, len(self.views),
            {name: r.as_dict() for name, r in solution.per_method.items()}, self.intrinsics, s.board,
        )
        log.info("calibration: %s from %d views (%d visited), method %s", plan.mount, len(self.views),
                 self.visited, solution.method)
        return CalibrationRun(solution, calibration, tuple(self.views), self.visited, dict(self.rejected))
