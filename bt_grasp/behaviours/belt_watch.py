"""Watching a running belt: frames at a rate, their detections handed over the cell's perception latency after the
frame was taken, each kept in the track of the object it shows (``bt_grasp.perception.belt_track``).

Every frame goes through the perception pipeline (the same objects ``PerceiveAll`` would list: any colour, any
shape), in the base frame through the calibration at the time of the frame (a wrist camera's pose from the joints
then). A detection becomes a measurement of an object only when it is whole and on the belt: fully inside the
picture (an object cut by the picture's edge is seen shorter, its centre pulled inwards: 2 cm at the edge of the
fixed camera's view), centred over the belt, not the robot's own gripper (the arm hovers over the belt in the
pipeline's region of interest: a cluster around the tool's axis is the gripper), and, with a colour asked for, of
that colour. Each arrived frame's detections are matched to the tracks by where the tracks predict their objects
(along the belt within four sigma of the prediction or 3 cm, across within 3 cm); the others start tracks. The
belt's encoder, when it has one, is read every tick into the log every track shares.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.perceive import camera_pose
from bt_grasp.perception.belt_track import BeltAxis, BeltTrack, EncoderLog
from bt_grasp.scene.conveyor import Conveyor
from bt_grasp.seeds import Stream

if TYPE_CHECKING:
    from bt_grasp.behaviours.base import RobotLeaf
    from bt_grasp.interfaces import RGBDFrame
    from bt_grasp.perception.results import Detection
    from bt_grasp.scene.format import Scene

#: a detection whose footprint comes this close to the picture's edge is not whole, px
EDGE_PX = 6
#: a detection centred this close to the tool's axis, up to the tool's height, is the gripper, m
GRIPPER_RADIUS_M = 0.09
#: a detection is matched to a track within this across the belt, m ...
GATE_ACROSS_M = 0.03
#: ... and within this along it, or four sigma of the prediction when larger, m
GATE_ALONG_M = 0.03
#: a full frame (colour, depth, cloud) goes to the log every this many frames
FRAME_LOG_EVERY = 5


def conveyor_named(scene: Scene, name: str) -> Conveyor | None:
    fixture = scene.fixture(name)
    return fixture if isinstance(fixture, Conveyor) else None


def belt_axis(scene: Scene, belt: Conveyor) -> BeltAxis:
    """The belt in the robot's base frame (installation data: the scene's fixture and where the robot stands)."""
    T_base_world = np.linalg.inv(scene.T_world_base())
    origin = (T_base_world @ np.array([*belt.upstream_end_world(), 1.0]))[:3]
    direction = T_base_world[:3, :3] @ belt.axis_world
    return BeltAxis(origin, direction, float(belt.length_m), float(belt.width_m), float(belt.speed_m_s))


@dataclass
class _Frame:
    ready_ns: int
    t_s: float
    detections: tuple[Detection, ...]


@dataclass
class BeltWatch:
    """The frames in flight and the tracks of one belt (handed from TrackOnBelt to InterceptPick)."""

    axis: BeltAxis
    belt_name: str
    color: str = ""
    encoder_log: EncoderLog | None = None
    tracks: list[BeltTrack] = field(default_factory=list)
    frames: int = 0
    _in_flight: deque[_Frame] = field(default_factory=deque)
    _last_capture_s: float = float("-inf")

    def read_encoder(self, leaf: RobotLeaf) -> None:
        encoder = leaf.cell.encoders.get(self.belt_name)
        if encoder is None:
            return
        if self.encoder_log is None:
            self.encoder_log = EncoderLog(resolution_m=1.0 / encoder.counts_per_m)
        self.encoder_log.add(leaf.now_s(), encoder.counts() / encoder.counts_per_m)

    def step(self, leaf: RobotLeaf, rate_hz: float, look: bool = True) -> list[BeltTrack]:
        """One tick: read the encoder, take a frame when one is due (``look``), hand over the frames whose time
        has come; returns the tracks a detection was added to."""
        self.read_encoder(leaf)
        now = leaf.now_s()
        if look and rate_hz > 0 and now - self._last_capture_s >= 1.0 / rate_hz - 1e-9:
            self._last_capture_s = now
            self._capture(leaf)
        now_ns = leaf.cell.clock.now_ns()
        updated: list[BeltTrack] = []
        while self._in_flight and self._in_flight[0].ready_ns <= now_ns:
            frame = self._in_flight.popleft()
            updated.extend(self._associate(frame))
        return updated

    def _capture(self, leaf: RobotLeaf) -> None:
        # deferred: Open3D and OpenCV come with it; a tree loads and validates without them
        from bt_grasp.behaviours.fixture_mask import without_fixtures
        from bt_grasp.perception.pipeline import perceive  # deferred: as above

        cell = leaf.cell
        T_base_camera = camera_pose(cell)
        if T_base_camera is None:
            return
        t_s = leaf.now_s()
        T_base_tcp = cell.kinematics.fk(cell.robot.joint_positions())
        frame = cell.camera.capture()
        if frame is None:
            return
        self.frames += 1
        if self.frames % FRAME_LOG_EVERY == 1:
            cell.media.frame(frame, T_base_camera)
        result = without_fixtures(perceive(frame, T_base_camera, cell.perception_config,
                                           seed=cell.seeds.integer(Stream.PERCEPTION)), cell.scene)
        whole = tuple(d for d in result.others if self._measurable(d, frame, T_base_camera, T_base_tcp))
        self._in_flight.append(_Frame(cell.detections_ready_ns(frame.stamp_ns), t_s, whole))

    def _measurable(self, det: Detection, frame: RGBDFrame, T_base_camera: NDArray[np.float64],
                    T_base_tcp: NDArray[np.float64]) -> bool:
        """Whole, on the belt, not the gripper, of the colour asked for (the module docstring)."""
        c = np.asarray(det.centroid_base_m, dtype=float)
        if abs(self.axis.across(c)) > self.axis.width_m / 2 or not 0.0 <= self.axis.along(c) <= self.axis.length_m:
            return False
        if float(np.hypot(*(c[:2] - T_base_tcp[:2, 3]))) < GRIPPER_RADIUS_M and \
                det.table_z_m + det.size_m[2] > T_base_tcp[2, 3] - 0.05:
            return False
        if self.color and self.color not in (det.label, det.color_name):
            return False
        return _whole_in_picture(det, frame, T_base_camera)

    def _associate(self, frame: _Frame) -> list[BeltTrack]:
        updated: list[BeltTrack] = []
        free = list(self.tracks)
        for det in sorted(frame.detections, key=lambda d: -self.axis.along(np.asarray(d.centroid_base_m))):
            c = np.asarray(det.centroid_base_m, dtype=float)
            along, across = self.axis.along(c), self.axis.across(c)
            best, best_gap = None, float("inf")
            for track in free:
                p = track.predict(frame.t_s)
                gap = abs(along - p.along_m)
                gate = max(GATE_ALONG_M, 4.0 * track.innovation_sigma_m(frame.t_s))
                if gap <= gate and abs(across - track.across_m) <= GATE_ACROSS_M and gap < best_gap:
                    best, best_gap = track, gap
            if best is None:
                track = BeltTrack(self.axis, frame.t_s, det, self.encoder_log)
                self.tracks.append(track)
                updated.append(track)
                continue
            free.remove(best)
            best.add(frame.t_s, det)
            updated.append(best)
        # an object gone past the belt's end is no longer tracked
        now = frame.t_s
        self.tracks = [t for t in self.tracks if t.predict(now).along_m <= self.axis.length_m + 0.05]
        return updated


def _whole_in_picture(det: Detection, frame: RGBDFrame, T_base_camera: NDArray[np.float64]) -> bool:
    """The detection's footprint, at its base and at its top, projects at least EDGE_PX inside the picture."""
    footprint = det.footprint_base_m or ((det.centroid_base_m[0], det.centroid_base_m[1]),)
    z_low, z_high = det.table_z_m, det.table_z_m + det.size_m[2]
    T_camera_base = np.linalg.inv(T_base_camera)
    intr = frame.intrinsics
    for x, y in footprint:
        for z in (z_low, z_high):
            p = T_camera_base @ np.array([x, y, z, 1.0])
            if p[2] <= 1e-3:
                return False
            u = intr.fx_px * p[0] / p[2] + intr.cx_px
            v = intr.fy_px * p[1] / p[2] + intr.cy_px
            if not (EDGE_PX <= u <= intr.width_px - 1 - EDGE_PX and EDGE_PX <= v <= intr.height_px - 1 - EDGE_PX):
                return False
    return True


@dataclass
class BeltTarget:
    """What TrackOnBelt hands to InterceptPick: the object's track and the watch that keeps it (frames in flight,
    the encoder's log), so the intercept goes on where the tracking left off."""

    watch: BeltWatch
    track: BeltTrack
