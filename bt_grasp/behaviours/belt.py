"""BeltWaitPose and TrackOnBelt: the arm ready upstream over a running belt, and an object tracked as it comes.

* ``BeltWaitPose`` moves the tool, pointing down, over the belt's centre line ``height`` above its surface, upstream:
  ``ahead`` downstream of the first point of the belt that (1) the arm reaches (a top-down grasp and the pose above
  it with one arm configuration family: ``bt_grasp.motion.intercept.reach_window``, from the belt's geometry in the
  scene and the arm's kinematic model), (2) lies within ``reach`` of the robot's base horizontally (an arm
  stretched further needs long joint motions to come back: 1 s instead of 0.5), and (3) a fixed camera sees (from
  the calibration and the camera's intrinsics; a wrist camera looks where the tool is). From there the arm starts
  every intercept moving downstream with the object. The tool's x axis points downstream, so a wrist camera (behind
  the tool) looks at the belt coming; its default height keeps that camera beyond the D435's minimum range from the
  objects' tops.
* ``TrackOnBelt`` watches the belt (``bt_grasp.behaviours.belt_watch``) until an object (of ``color``, when
  given) has ``min_detections`` detections and is still far enough upstream for an intercept (its predicted
  place ``lead`` seconds ahead, plus what an intercept rides with it, inside the reach), and hands the most
  downstream such object over as ``target``. FAILURE ``NO_DETECTION`` when none comes within ``timeout``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.base import HaltCancelsJob, RobotLeaf
from bt_grasp.behaviours.belt_watch import BeltTarget, BeltWatch, belt_axis, conveyor_named
from bt_grasp.behaviours.motion_job import MotionJob, PathFailure, Segment
from bt_grasp.behaviours.reasons import MOTION_REASONS, FailureReason
from bt_grasp.interfaces import Mount
from bt_grasp.perception.belt_track import BeltAxis, BeltTrack
from bt_grasp.tree.node_api import Status, action, input_port, output_port

if TYPE_CHECKING:
    from bt_grasp.scene.format import Scene

_BELT = input_port("belt", str, description="the conveyor fixture's name", required=True)
#: BeltWaitPose's default tcp height over the belt with a fixed camera, m (clear of the objects passing under) ...
FIXED_CAMERA_HEIGHT_M = 0.22
#: ... and with a wrist camera (9 cm above the tcp: 0.33 m above a 7 cm object's top, beyond the D435's 0.28 m)
WRIST_CAMERA_HEIGHT_M = 0.32
#: the nominal grasp of the reach window: the tcp this far above the belt's surface (a 5 cm box's middle)
NOMINAL_GRASP_Z_M = 0.03


class _OnBelt(RobotLeaf):
    """A leaf whose ``belt`` port names a conveyor of the scene (checked at load when the tree names it literally)."""

    def check_scene(self, scene: Scene) -> str | None:
        if self.ports.key("belt") is not None:
            return None
        name = self.ports.require("belt", str)
        if conveyor_named(scene, name) is None:
            belts = ", ".join(f.name for f in scene.fixtures if f.kind == "conveyor") or "none"
            return f"port 'belt': no conveyor named '{name}' in the scene (conveyors: {belts})"
        return None


def nominal_window(leaf: RobotLeaf, axis: BeltAxis, hover_m: float) -> tuple[float, float, NDArray[np.float64]] | None:
    """The reach along the belt's centre line of a top-down grasp (tool x downstream) at the nominal height and of
    the pose ``hover_m`` above it, walked from the belt's point nearest the robot with the scene's home posture's
    configuration family: (lo, hi, its configurations), or None when the arm reaches none of the belt."""
    # deferred: ruckig and pinocchio come with it; a tree loads and validates without them
    from bt_grasp.motion.intercept import BeltGrasp, InterceptSettings, reach_window, tool_down

    yaw = float(np.arctan2(axis.direction[1], axis.direction[0]))
    grasp = BeltGrasp(np.zeros(3), tool_down(np.zeros(3), yaw)[:3, :3], 0.05)
    nearest = float(np.clip(axis.along(np.zeros(3)), 0.0, axis.length_m))  # the belt's point nearest the base
    home = np.asarray(leaf.cell.scene.robot.home_q_rad, dtype=float)
    window = reach_window(leaf.cell.kinematics, lambda s: axis.point(s, 0.0, axis.surface_z_m + NOMINAL_GRASP_Z_M),
                          grasp, hover_m, home, axis.length_m, nearest, InterceptSettings().max_reach_m)
    if window.empty:
        return None
    return window.lo, window.hi, window.q


def _within_reach(axis: BeltAxis, reach_m: float) -> float:
    """The first point of the belt's centre line within ``reach_m`` of the robot's base horizontally (0: none is)."""
    along_nearest = axis.along(np.zeros(3))
    gap = float(np.hypot(*axis.point(along_nearest, 0.0, 0.0)[:2]))
    if gap >= reach_m:
        return 0.0
    return max(0.0, along_nearest - float(np.sqrt(reach_m**2 - gap**2)))


@action(
    ports=[
        _BELT,
        input_port("height", float, 0.0, "the tcp above the belt's surface, m (0: 0.22 with a fixed camera, 0.32 "
                   "with a wrist camera)"),
        input_port("ahead", float, 0.05, "downstream of the first point of the belt reached and seen, m"),
        input_port("reach", float, 0.65, "the waiting tcp at most this far from the robot's base horizontally, m"),
    ],
    reasons=(FailureReason.BAD_INPUT, *MOTION_REASONS),
    needs_robot=True,
)
class BeltWaitPose(HaltCancelsJob, _OnBelt):
    """Move the tool over the belt's upstream reach, pointing down, ready to intercept what comes."""

    def initialise(self) -> None:
        self._early: Status | None = None
        self.job: MotionJob | None = None
        belt = conveyor_named(self.cell.scene, self.ports.require("belt", str))
        if belt is None:
            self._early = self.fail(FailureReason.BAD_INPUT, f"no conveyor named '{self.ports.get('belt', str)}'")
            return
        axis = belt_axis(self.cell.scene, belt)
        height = self.ports.require("height", float) or (
            WRIST_CAMERA_HEIGHT_M if self.cell.camera.mount == Mount.EYE_IN_HAND else FIXED_CAMERA_HEIGHT_M)
        window = nominal_window(self, axis, height - NOMINAL_GRASP_Z_M)
        if window is None:
            self._early = self.fail(FailureReason.IK_UNREACHABLE, f"the arm reaches no part of the belt '{belt.name}'")
            return
        lo, hi, qs = window
        start = max(lo, _within_reach(axis, self.ports.require("reach", float)), self._first_seen(axis))
        along = min(start + self.ports.require("ahead", float), hi)
        q_wait = self._configuration(axis, along, height, qs[int(np.clip(round((along - lo) / 0.01), 0, len(qs) - 1))])
        if q_wait is None:
            self._early = self.fail(FailureReason.IK_UNREACHABLE, f"no arm configuration {height:.2f} m over the belt "
                                    f"{along:.2f} m from its upstream end")
            return
        # deferred: scipy comes with it; a tree loads and validates without it
        from bt_grasp.behaviours.motion_leaves import plan_to_joints_fn
        from bt_grasp.motion.planning_scene import PlanningScene  # deferred: as above

        self.feedback_message = f"to {along:.2f} m along the belt (reach {lo:.2f} to {hi:.2f} m), {height:.2f} m up"
        path = plan_to_joints_fn(self, q_wait, PlanningScene.from_scene(self.cell.scene))
        self.job = MotionJob(self.cell, [Segment("to the belt's waiting pose", path)])

    def _first_seen(self, axis: BeltAxis) -> float:
        """The first point of the belt's centre line a fixed camera sees (0 for a wrist camera or none calibrated)."""
        calibration = self.cell.calibration
        if calibration is None or calibration.mount != Mount.EYE_TO_HAND:
            return 0.0
        T_camera_base = np.linalg.inv(calibration.T_base_camera_at(None))
        intr = self.cell.camera.intrinsics
        for along in np.arange(0.0, axis.length_m, 0.01):
            p = T_camera_base @ np.array([*axis.point(float(along), 0.0, axis.surface_z_m + NOMINAL_GRASP_Z_M), 1.0])
            if p[2] <= 0:
                continue
            u, v = intr.fx_px * p[0] / p[2] + intr.cx_px, intr.fy_px * p[1] / p[2] + intr.cy_px
            if 0 <= u <= intr.width_px - 1 and 0 <= v <= intr.height_px - 1:
                return float(along)
        return 0.0

    def _configuration(self, axis: BeltAxis, along: float, height: float, seed: NDArray[np.float64]
                       ) -> NDArray[np.float64] | None:
        # deferred: pinocchio comes with it; a tree loads and validates without it
        from bt_grasp.motion.intercept import nearest_ik, tool_down

        yaw = float(np.arctan2(axis.direction[1], axis.direction[0]))
        return nearest_ik(self.cell.kinematics, tool_down(axis.point(along, 0.0, axis.surface_z_m + height), yaw),
                          seed)

    def update(self) -> Status:
        if self._early is not None:
            return self._early
        assert self.job is not None
        outcome = self.job.update()
        if outcome is None:
            return Status.RUNNING
        if isinstance(outcome, PathFailure):
            self.job.cancel()
            return self.fail(outcome.reason, outcome.sentence)
        return Status.SUCCESS


@action(
    ports=[
        _BELT,
        input_port("color", str, "", "only objects of this colour name (empty: any object)"),
        input_port("min_detections", int, 0, "detections of the object before it is handed over (0: 4, 3 on a belt "
                   "faster than 35 cm/s)"),
        input_port("rate", float, 15.0, "frames per second while an object is tracked (simulated time)"),
        input_port("idle_rate", float, 0.0, "frames per second while none is (0: 5, 15 on a belt faster than 35 cm/s)"),
        input_port("lead", float, 0.0, "the object must be this long of belt travel from leaving the reach, "
                   "beyond what an intercept rides with it, s (0: 1.0, 0.3 on a belt faster than 35 cm/s)"),
        input_port("timeout", float, 30.0, "NO_DETECTION after this long with no object to hand over, s"),
        output_port("target", object, "the object tracked (for InterceptPick)", default="{belt_target}"),
    ],
    reasons=(FailureReason.BAD_INPUT, FailureReason.NO_DETECTION, FailureReason.CALIBRATION_MISSING),
    needs_robot=True,
)
class TrackOnBelt(_OnBelt):
    """Watch the belt until an object comes that can still be intercepted; hand it over with its track."""

    def initialise(self) -> None:
        self._early: Status | None = None
        belt = conveyor_named(self.cell.scene, self.ports.require("belt", str))
        if belt is None:
            self._early = self.fail(FailureReason.BAD_INPUT, f"no conveyor named '{self.ports.get('belt', str)}'")
            return
        if self.cell.calibration is None:
            self._early = self.fail(FailureReason.CALIBRATION_MISSING, "no camera calibration loaded")
            return
        axis = belt_axis(self.cell.scene, belt)
        self.watch = BeltWatch(axis, belt.name, self.ports.get("color", str) or "")
        # deferred: ruckig comes with it; a tree loads and validates without it
        from bt_grasp.motion.intercept import FAST_BELT_M_S, InterceptSettings

        settings = InterceptSettings.for_belt(axis.nominal_speed_m_s)
        # a fast belt leaves the arm less time: objects are looked for at the tracking rate and handed over sooner
        # (the encoder carries the track), and the approach is given what the arm needs, not a second more
        fast = abs(axis.nominal_speed_m_s) > FAST_BELT_M_S
        self._min_detections = self.ports.require("min_detections", int) or (3 if fast else 4)
        self._idle_rate = self.ports.require("idle_rate", float) or (15.0 if fast else 5.0)
        lead = self.ports.require("lead", float) or (0.3 if fast else 1.0)
        window = nominal_window(self, axis, settings.hover_m)
        self._latest_along = -1.0 if window is None else window[1] - settings.margin_m - abs(
            axis.nominal_speed_m_s) * (settings.match_travel_s() + lead)
        self._started = self.now_s()

    def update(self) -> Status:
        if self._early is not None:
            return self._early
        watch = self.watch
        rate = self.ports.require("rate", float) if watch.tracks else self._idle_rate
        watch.step(self, rate)
        now = self.now_s()
        ready = [t for t in watch.tracks if self._ready(t, now)]
        if ready:
            track = max(ready, key=lambda t: t.predict(now).along_m)
            self.ports.set("target", BeltTarget(watch, track))
            p = track.predict(now)
            self.feedback_message = (f"{track.detection.label} {track.detections} detections, {p.along_m:.3f} m along "
                                     f"the belt at {np.linalg.norm(p.velocity_m_s) * 100:.1f} cm/s")
            return Status.SUCCESS
        if now - self._started > self.ports.require("timeout", float):
            return self.fail(FailureReason.NO_DETECTION, f"no object to intercept came within "
                             f"{self.ports.require('timeout', float):.0f} s ({len(watch.tracks)} tracked)")
        self.feedback_message = f"{len(watch.tracks)} object(s) tracked, {watch.frames} frame(s)"
        return Status.RUNNING

    def _ready(self, track: BeltTrack, now_s: float) -> bool:
        return (track.detections >= self._min_detections
                and track.predict(now_s).along_m <= self._latest_along)
