"""LookAt: move a wrist (eye-in-hand) camera so that it looks at a point, a detection or the work area.

The observation strategy of a wrist camera is coarse to fine and written in the tree: ``LookAt
view="workspace"`` (a survey view from high above the work area's centre), ``Perceive``, ``LookAt
target="{target}"`` (a close view above the target), ``Perceive`` again to refine the pose, then the grasp.

Geometry: the tool points straight down (tool z = base -z) and is yawed so that tool x points away from the
robot base; the tool is placed so that the camera's optical axis (from the calibration, ``T_tool_camera``)
passes through the point at ``distance`` metres from the camera. The fingers hang 0.1-0.15 m below the
camera, closer than the D435's minimum depth range (0.28 m), so they never enter the depth image perception
uses; views are also chosen so the object lies beyond that range (distance >= 0.35 m).
With an eye-to-hand camera the leaf has nothing to move: it succeeds and says so.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.base import RobotLeaf
from bt_grasp.behaviours.motion_job import Segment
from bt_grasp.behaviours.motion_leaves import _MovingLeaf, plan_to_pose_fn
from bt_grasp.behaviours.reasons import MOTION_REASONS, FailureReason
from bt_grasp.geometry import T_from_xyz_rpy, inv, make_T, rot_z
from bt_grasp.interfaces import Mount
from bt_grasp.tree.node_api import Status, action, input_port

if TYPE_CHECKING:
    from bt_grasp.perception.results import Detection
    from bt_grasp.scene.format import Scene

#: camera-to-point distance of the survey view and of a close view, m
SURVEY_DISTANCE_M = 0.62
CLOSE_DISTANCE_M = 0.40
#: the work-area point a survey looks at sits this far towards the robot from the workspace's centre, m
#: (the arm reaches a high view more easily there; the 55 x 42 degree view still covers the objects' area)
SURVEY_PULL_M = 0.02
#: a second look at one half of the work area (view="workspace-left" etc.), from this close, m: the survey's view
#: does not reach the work area's edges (a box at y = -0.31 m of the default +-0.35 m was never seen)
HALF_VIEW_DISTANCE_M = 0.45


def parse_point(text: str) -> NDArray[np.float64] | None:
    """'x;y;z' (BT.CPP's vector syntax) or 'x,y,z' -> array; None when it is not three numbers."""
    parts = [p for p in text.replace(",", ";").split(";") if p.strip()]
    if len(parts) != 3:
        return None
    try:
        return np.array([float(p) for p in parts], dtype=float)
    except ValueError:
        return None


def tool_pose_for_view(point_base: NDArray[np.float64], distance_m: float, T_tool_camera: NDArray[np.float64]
                       ) -> NDArray[np.float64]:
    """T_base_tool with the tool pointing down, tool x away from the base, camera axis through the point."""
    yaw = float(np.arctan2(point_base[1], point_base[0]))
    R_tool = rot_z(yaw) @ np.diag([1.0, -1.0, -1.0])
    z_cam = R_tool @ T_tool_camera[:3, 2]
    cam_position = point_base - distance_m * z_cam
    tool_position = cam_position - R_tool @ T_tool_camera[:3, 3]
    return make_T(R_tool, tool_position)


def view_point(leaf: RobotLeaf, view: str, target: Detection | None) -> tuple[NDArray[np.float64], float] | str:
    """(point in the base frame, default distance) for the ports, or a sentence saying what is wrong."""
    if target is not None:
        c = np.asarray(target.centroid_base_m, dtype=float)
        return c, CLOSE_DISTANCE_M
    if view == "workspace" or view.startswith("workspace-"):
        return workspace_view(leaf.cell.scene, view)
    point = parse_point(view)
    if point is None:
        return f"view '{view}' is {VIEW_CHOICES}"
    return point, CLOSE_DISTANCE_M


VIEW_CHOICES = ("neither 'workspace', 'workspace-near', 'workspace-far', 'workspace-left', 'workspace-right' nor a "
                "point 'x;y;z' in the base frame")


def workspace_view(scene: Scene, view: str) -> tuple[NDArray[np.float64], float] | str:
    """The survey of the whole work area ('workspace'), or a closer look at one half of it ('workspace-left':
    +y, '-right', '-near': towards the robot, '-far'): (point in the base frame, distance)."""
    ws = scene.workspace
    x0, x1 = (float(v) for v in ws.x_m)
    y0, y1 = (float(v) for v in ws.y_m)
    xm, ym = (x0 + x1) / 2, (y0 + y1) / 2
    to_base = inv(np.asarray(scene.T_world_base(), dtype=float))
    if view == "workspace":
        centre = (to_base @ np.array([xm, ym, 0.0, 1.0]))[:3]
        centre[:2] -= SURVEY_PULL_M * centre[:2] / max(float(np.linalg.norm(centre[:2])), 1e-9)
        return centre, SURVEY_DISTANCE_M
    half = view.removeprefix("workspace-")
    points = {"near": ((x0 + xm) / 2, ym), "far": ((xm + x1) / 2, ym), "left": (xm, (ym + y1) / 2),
              "right": (xm, (y0 + ym) / 2)}
    if half not in points:
        return f"view '{view}' is {VIEW_CHOICES}"
    x, y = points[half]
    return (to_base @ np.array([x, y, 0.0, 1.0]))[:3], HALF_VIEW_DISTANCE_M


@action(
    ports=[
        input_port("view", str, "workspace", "'workspace' (survey the work area), 'workspace-near', '-far', '-left' "
                   "or '-right' (a closer look at one half of it: a second look) or a point 'x;y;z' in the base "
                   "frame, m"),
        input_port("target", object, "", "a detection to look at (overrides view)"),
        input_port("distance", float, 0.0, "camera-to-point distance along the optical axis, m (0: 0.62 survey, "
                   "0.45 half, 0.40 close)"),
    ],
    reasons=(FailureReason.BAD_INPUT, FailureReason.CALIBRATION_MISSING, *MOTION_REASONS),
    needs_robot=True,
)
class LookAt(_MovingLeaf):
    """Move the wrist camera to look at the work area, a point or a detection (eye-in-hand views)."""

    def check_scene(self, scene: Scene) -> str | None:
        """A literal view that is not a point, or that the arm cannot reach with the scene's nominal camera
        mount, is a load error (file:line before anything runs)."""
        if Mount(scene.camera.mount) != Mount.EYE_IN_HAND or self.ports.key("view") is not None:
            return None
        view = self.ports.require("view", str)
        if view == "workspace" or self.ports.key("target") is not None:
            return None
        if view.startswith("workspace-"):
            looked = workspace_view(scene, view)
            if isinstance(looked, str):
                return looked
            point, distance = looked[0], self.ports.get("distance", float) or looked[1]
        else:
            parsed = parse_point(view)
            if parsed is None:
                return f"view '{view}' is {VIEW_CHOICES}"
            point, distance = parsed, self.ports.get("distance", float) or CLOSE_DISTANCE_M
        # deferred: pinocchio and coal come with it; a tree loads and validates without them
        from bt_grasp.motion.kinematics import ArmKinematics

        mount = scene.camera.eye_in_hand
        T_tool_camera = T_from_xyz_rpy(np.array(mount.xyz_m), np.deg2rad(mount.rpy_deg))
        kin = ArmKinematics()
        q_home = np.asarray(scene.robot.home_q_rad, dtype=np.float64)
        T_tool_tcp = inv(kin.fk_link(q_home, mount.parent_link)) @ kin.fk(q_home)
        if not kin.ik(tool_pose_for_view(point, distance, T_tool_camera) @ T_tool_tcp, q_home).ok:
            return (f"the view of ({point[0]:.3f}, {point[1]:.3f}, {point[2]:.3f}) m from {distance:.2f} m is out of "
                    "the arm's reach")
        return None

    def segments(self) -> list[Segment] | Status:
        # deferred: scipy comes with it; a tree loads and validates without it
        from bt_grasp.motion.planning_scene import PlanningScene

        calibration = self.cell.calibration
        if calibration is None:
            return self.fail(FailureReason.CALIBRATION_MISSING, "no camera calibration loaded")
        if calibration.mount != Mount.EYE_IN_HAND:
            self.cell.media.log("INFO", self.name, "eye-to-hand camera: nothing to move")
            self.feedback_message = "fixed camera: nothing to move"
            return Status.SUCCESS
        found = view_point(self, self.ports.get("view", str) or "workspace", self.input_detection("target"))
        if isinstance(found, str):
            return self.fail(FailureReason.BAD_INPUT, found)
        point, default_distance = found
        distance = self.ports.get("distance", float) or default_distance
        if not 0.3 <= distance <= 1.5:
            return self.fail(FailureReason.BAD_INPUT, f"view distance {distance} m is outside [0.3, 1.5]")
        kin = self.cell.kinematics
        q = self.cell.robot.joint_positions()
        T_tool_tcp = inv(kin.fk_link(q, calibration.tool_link)) @ kin.fk(q)
        T_tool_camera = np.asarray(calibration.T_base_camera_at(np.eye(4)), dtype=np.float64)  # camera in tool frame
        T_tool = tool_pose_for_view(point, distance, T_tool_camera)
        T_tcp = T_tool @ T_tool_tcp
        if not kin.ik(T_tcp, q).ok:
            return self.fail(FailureReason.IK_UNREACHABLE,
                               f"the view of ({point[0]:.3f}, {point[1]:.3f}, {point[2]:.3f}) from {distance:.2f} m "
                               "is out of the arm's reach")
        self.cell.media.log("INFO", self.name, f"view of ({point[0]:.3f}, {point[1]:.3f}, {point[2]:.3f}) m from "
                            f"{distance:.2f} m: tool at ({T_tool[0, 3]:.3f}, {T_tool[1, 3]:.3f}, {T_tool[2, 3]:.3f})")
        self.feedback_message = f"looking at ({point[0]:.2f}, {point[1]:.2f}, {point[2]:.2f}) from {distance:.2f} m"
        return [Segment("view", plan_to_pose_fn(self, T_tcp, PlanningScene.from_scene(self.cell.scene)))]
