"""What ``perceive`` reports of each frame, in the frame every output is given in (base frame, or camera frame).

Typed, frozen: :class:`FrameReport` holds :class:`ObjectReport` s (in the order a tree's ``PerceiveAll`` lists them),
each with its ranked :class:`GraspReport` s. :meth:`FrameReport.as_json` keeps numbers as numbers (full precision:
two runs on the same frames compare exactly); the command line prints the table.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import Mat4, quat_wxyz
from bt_grasp.perception.results import Detection, GraspCandidate
from bt_grasp.sensing.perceive_frame import FramePerception

Vec3 = tuple[float, float, float]
JsonObject = dict[str, object]


def _vec(v: NDArray[np.float64]) -> Vec3:
    return (float(v[0]), float(v[1]), float(v[2]))


@dataclass(frozen=True)
class GraspReport:
    rank: int
    T_frame_tcp: Mat4  # the grasp pose (tcp z: approach, tcp y: closing direction)
    T_frame_pregrasp: Mat4
    width_m: float
    score: float
    reason: str

    @property
    def position_m(self) -> Vec3:
        return _vec(self.T_frame_tcp[:3, 3])

    def as_json(self) -> JsonObject:
        q = quat_wxyz(self.T_frame_tcp)
        if q[0] < 0:
            q = -q
        return {"rank": self.rank, "position_m": list(self.position_m), "quat_wxyz": [float(v) for v in q],
                "matrix": [[float(v) for v in row] for row in self.T_frame_tcp], "width_m": self.width_m,
                "score": self.score, "reason": self.reason}


@dataclass(frozen=True)
class ObjectReport:
    index: int
    label: str  # the colour name when the colour matched, else "object"
    class_name: str  # the learned detector's class ("" when none named it)
    class_score: float
    shape_class: str
    color_name: str
    centroid_m: Vec3  # the box centre, in the report's frame
    size_m: Vec3  # length, width, height
    yaw_deg: float  # the footprint's long side about the table normal (base frame; the table frame without one)
    T_frame_box: Mat4
    point_count: int
    confidence: float
    grasp_status: str
    grasp_message: str
    grasps: tuple[GraspReport, ...]

    @property
    def name(self) -> str:
        return self.class_name or self.label

    def as_json(self) -> JsonObject:
        return {"index": self.index, "label": self.label, "class": self.class_name, "class_score": self.class_score,
                "shape_class": self.shape_class, "color": self.color_name, "centroid_m": list(self.centroid_m),
                "size_m": list(self.size_m), "yaw_deg": self.yaw_deg, "points": self.point_count,
                "confidence": self.confidence, "grasp_status": self.grasp_status, "grasp_message": self.grasp_message,
                "grasps": [g.as_json() for g in self.grasps]}


@dataclass(frozen=True)
class FrameReport:
    index: int
    stamp_ns: int
    frame_id: str
    status: str
    message: str
    objects: tuple[ObjectReport, ...]
    T_base_camera: Mat4 | None

    def as_json(self) -> JsonObject:
        out: JsonObject = {"index": self.index, "stamp_ns": self.stamp_ns, "frame_id": self.frame_id,
                           "status": self.status, "message": self.message,
                           "objects": [o.as_json() for o in self.objects]}
        if self.T_base_camera is not None:
            out["T_base_camera"] = [[float(v) for v in row] for row in self.T_base_camera]
        return out


def _box_pose(det: Detection) -> Mat4:
    T = np.eye(4)
    if det.obb is not None:
        return np.asarray(det.obb.T_base_box, dtype=float)
    c, s = math.cos(det.yaw_rad), math.sin(det.yaw_rad)
    T[:3, :3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    T[:3, 3] = det.centroid_base_m
    return T


def _grasp(rank: int, candidate: GraspCandidate, T_out: Mat4) -> GraspReport:
    return GraspReport(rank, T_out @ np.asarray(candidate.T_base_tcp_grasp, dtype=float),
                       T_out @ np.asarray(candidate.T_base_tcp_pregrasp, dtype=float), float(candidate.width_m),
                       float(candidate.score), candidate.reason)


def frame_report(index: int, seen: FramePerception) -> FrameReport:
    """The report of one perceived frame, every pose in the placement's output frame."""
    placement = seen.placement
    result = seen.result
    frame_id = placement.frame_id if placement is not None else "camera_color_optical_frame"
    if placement is None:
        return FrameReport(index, seen.frame.stamp_ns, frame_id, result.status.value, result.message, (), None)
    T_out = np.asarray(placement.T_out_pipeline, dtype=float)
    objects = []
    for i, (det, grasps) in enumerate(zip(result.others, seen.grasps, strict=True)):
        T_box = T_out @ _box_pose(det)
        objects.append(ObjectReport(
            index=i, label=det.label, class_name=det.class_name, class_score=float(det.class_score),
            shape_class=det.shape_class.value, color_name=det.color_name, centroid_m=_vec(T_box[:3, 3]),
            size_m=(float(det.size_m[0]), float(det.size_m[1]), float(det.size_m[2])),
            yaw_deg=math.degrees(det.yaw_rad), T_frame_box=T_box, point_count=int(det.point_count),
            confidence=float(det.confidence), grasp_status=grasps.status.value, grasp_message=grasps.message,
            grasps=tuple(_grasp(k, c, T_out) for k, c in enumerate(grasps.candidates)),
        ))
    return FrameReport(index, seen.frame.stamp_ns, frame_id, result.status.value, result.message, tuple(objects),
                       placement.T_base_camera)


def dropped_report(index: int, frame_id: str) -> FrameReport:
    """A frame that did not arrive (a timeout, or the recording's end)."""
    return FrameReport(index, -1, frame_id, "dropped", "no frame arrived (a dropped frame, or the recording's end)",
                       (), None)
