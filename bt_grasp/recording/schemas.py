"""Foxglove well-known messages (protobuf) built from numpy inputs, and the typed marker inputs.

Every builder takes simulated time in ns and returns a protobuf message ready to serialise. Transforms
are 4x4 homogeneous matrices named ``T_parent_child`` (maps child-frame points to the parent frame).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from foxglove_schemas_protobuf.ArrowPrimitive_pb2 import ArrowPrimitive
from foxglove_schemas_protobuf.CameraCalibration_pb2 import CameraCalibration
from foxglove_schemas_protobuf.Color_pb2 import Color
from foxglove_schemas_protobuf.CompressedImage_pb2 import CompressedImage
from foxglove_schemas_protobuf.CubePrimitive_pb2 import CubePrimitive
from foxglove_schemas_protobuf.FrameTransform_pb2 import FrameTransform
from foxglove_schemas_protobuf.FrameTransforms_pb2 import FrameTransforms
from foxglove_schemas_protobuf.ImageAnnotations_pb2 import ImageAnnotations
from foxglove_schemas_protobuf.KeyValuePair_pb2 import KeyValuePair
from foxglove_schemas_protobuf.Log_pb2 import Log
from foxglove_schemas_protobuf.PackedElementField_pb2 import PackedElementField
from foxglove_schemas_protobuf.Point2_pb2 import Point2
from foxglove_schemas_protobuf.PointCloud_pb2 import PointCloud
from foxglove_schemas_protobuf.PointsAnnotation_pb2 import PointsAnnotation
from foxglove_schemas_protobuf.Pose_pb2 import Pose
from foxglove_schemas_protobuf.Quaternion_pb2 import Quaternion
from foxglove_schemas_protobuf.RawImage_pb2 import RawImage
from foxglove_schemas_protobuf.SceneEntity_pb2 import SceneEntity
from foxglove_schemas_protobuf.SceneEntityDeletion_pb2 import SceneEntityDeletion
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from foxglove_schemas_protobuf.TextAnnotation_pb2 import TextAnnotation
from foxglove_schemas_protobuf.TextPrimitive_pb2 import TextPrimitive
from foxglove_schemas_protobuf.Vector3_pb2 import Vector3
from google.protobuf.message import Message
from google.protobuf.timestamp_pb2 import Timestamp
from numpy.typing import ArrayLike, NDArray

#: protobuf classes of every Foxglove schema a bt_grasp log uses, by full name
PROTOBUF_CLASSES: dict[str, type[Message]] = {
    cls.DESCRIPTOR.full_name: cls
    for cls in (CompressedImage, RawImage, CameraCalibration, PointCloud, FrameTransforms, SceneUpdate, Log,
                ImageAnnotations)
}

RGBA = tuple[float, float, float, float]


@dataclass(frozen=True)
class BoxMarker:
    """An oriented box (a detection) drawn as a cube on /perception/detections.

    ``T_base_box``: 4x4 pose of the box centre in the base frame; ``size_m``: edge lengths along the box's
    x, y, z axes in metres; ``rgba``: colour components in [0, 1]; ``label``: text drawn above the box.
    """

    id: str
    T_base_box: ArrayLike
    size_m: tuple[float, float, float]
    rgba: RGBA = (0.1, 0.6, 1.0, 0.5)
    label: str = ""


@dataclass(frozen=True)
class PoseMarker:
    """A pose (a grasp candidate) drawn as x/y/z axis arrows on /perception/grasps.

    ``T_base_pose``: 4x4 pose in the base frame; ``length_m``: arrow length; ``label``: text at the origin;
    ``rgba``: colour of the approach (z) arrow; x and y are red and green.
    """

    id: str
    T_base_pose: ArrayLike
    length_m: float = 0.08
    label: str = ""
    rgba: RGBA = (0.1, 0.3, 1.0, 1.0)
    metadata: dict[str, str] = field(default_factory=dict)


def timestamp(stamp_ns: int) -> Timestamp:
    seconds, nanos = divmod(int(stamp_ns), 1_000_000_000)
    return Timestamp(seconds=seconds, nanos=nanos)


def quat_xyzw(R: NDArray[np.float64]) -> tuple[float, float, float, float]:
    """Unit quaternion (x, y, z, w) of a rotation matrix (Shepperd's method; cheaper than scipy per call)."""
    m00, m01, m02 = float(R[0, 0]), float(R[0, 1]), float(R[0, 2])
    m10, m11, m12 = float(R[1, 0]), float(R[1, 1]), float(R[1, 2])
    m20, m21, m22 = float(R[2, 0]), float(R[2, 1]), float(R[2, 2])
    trace = m00 + m11 + m22
    if trace > 0.0:
        s = 2.0 * math.sqrt(trace + 1.0)
        w, x, y, z = 0.25 * s, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s
    elif m00 > m11 and m00 > m22:
        s = 2.0 * math.sqrt(1.0 + m00 - m11 - m22)
        w, x, y, z = (m21 - m12) / s, 0.25 * s, (m01 + m10) / s, (m02 + m20) / s
    elif m11 > m22:
        s = 2.0 * math.sqrt(1.0 + m11 - m00 - m22)
        w, x, y, z = (m02 - m20) / s, (m01 + m10) / s, 0.25 * s, (m12 + m21) / s
    else:
        s = 2.0 * math.sqrt(1.0 + m22 - m00 - m11)
        w, x, y, z = (m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, 0.25 * s
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    return x / norm, y / norm, z / norm, w / norm


def as_matrix(T: object) -> NDArray[np.float64]:
    """``T`` (anything numpy reads as numbers) as a 4x4 float matrix; a ValueError if it is not one."""
    M = np.asarray(T, dtype=np.float64)
    if M.shape != (4, 4):
        raise ValueError(f"a transform must be a 4x4 matrix, got shape {M.shape}")
    return M


def pose(T: ArrayLike) -> Pose:
    M = as_matrix(T)
    x, y, z, w = quat_xyzw(M)
    return Pose(
        position=Vector3(x=float(M[0, 3]), y=float(M[1, 3]), z=float(M[2, 3])),
        orientation=Quaternion(x=x, y=y, z=z, w=w),
    )


def frame_transforms(stamp_ns: int, transforms: Sequence[tuple[str, str, ArrayLike]]) -> FrameTransforms:
    msg = FrameTransforms()
    ts = timestamp(stamp_ns)
    for parent, child, T in transforms:
        M = as_matrix(T)
        x, y, z, w = quat_xyzw(M)
        msg.transforms.append(
            FrameTransform(
                timestamp=ts,
                parent_frame_id=parent,
                child_frame_id=child,
                translation=Vector3(x=float(M[0, 3]), y=float(M[1, 3]), z=float(M[2, 3])),
                rotation=Quaternion(x=x, y=y, z=z, w=w),
            )
        )
    return msg


def compressed_image(
    stamp_ns: int, rgb: NDArray[np.uint8], frame_id: str, fmt: str = "jpeg", jpeg_quality: int = 90
) -> CompressedImage:
    check_color_image(rgb, fmt)
    import cv2  # here: a writer process loads OpenCV at its first image only

    bgr = np.ascontiguousarray(rgb[:, :, ::-1])
    if fmt == "jpeg":
        ok, buf = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, int(jpeg_quality)])
    elif fmt == "png":
        ok, buf = cv2.imencode(".png", bgr, [cv2.IMWRITE_PNG_COMPRESSION, 1])
    else:
        raise ValueError(f"unknown image format {fmt!r}; expected 'jpeg' or 'png'")
    if not ok:
        raise ValueError("OpenCV could not encode the colour image")
    return CompressedImage(timestamp=timestamp(stamp_ns), frame_id=frame_id, data=buf.tobytes(), format=fmt)


def camera_calibration(
    stamp_ns: int, frame_id: str, width: int, height: int, fx: float, fy: float, cx: float, cy: float
) -> CameraCalibration:
    """A pinhole camera without distortion (the simulated D435's colour stream), OpenCV pixel convention."""
    K = [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0]
    P = [fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0]
    R = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    return CameraCalibration(timestamp=timestamp(stamp_ns), frame_id=frame_id, width=int(width),
                             height=int(height), distortion_model="plumb_bob", D=[0.0] * 5, K=K, R=R, P=P)


def check_color_image(rgb: NDArray[np.uint8], fmt: str) -> None:
    """``ValueError`` unless ``rgb`` is an HxWx3 uint8 image and ``fmt`` "jpeg" or "png"."""
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.dtype != np.uint8:
        raise ValueError(f"a colour image must be HxWx3 uint8, got {rgb.shape} {rgb.dtype}")
    if fmt not in ("jpeg", "png"):
        raise ValueError(f"unknown image format {fmt!r}; expected 'jpeg' or 'png'")


def check_depth_image(depth_m: NDArray[np.floating], encoding: str) -> None:
    """``ValueError`` unless ``depth_m`` is HxW and ``encoding`` "16UC1" or "32FC1"."""
    if depth_m.ndim != 2:
        raise ValueError(f"a depth image must be HxW, got shape {depth_m.shape}")
    if encoding not in ("16UC1", "32FC1"):
        raise ValueError(f"unknown depth encoding {encoding!r}; expected '16UC1' or '32FC1'")


def depth_image(
    stamp_ns: int, depth_m: NDArray[np.floating], frame_id: str, encoding: str = "16UC1"
) -> RawImage:
    """Depth in metres as a RawImage: ``16UC1`` (millimetres, 0 = invalid, the RealSense convention) or
    ``32FC1`` (metres)."""
    check_depth_image(depth_m, encoding)
    height, width = depth_m.shape
    if encoding == "16UC1":
        mm = np.nan_to_num(np.asarray(depth_m, dtype=np.float64) * 1000.0, nan=0.0, posinf=0.0, neginf=0.0)
        data = np.clip(np.rint(mm), 0, 65535).astype("<u2").tobytes()
        step = width * 2
    elif encoding == "32FC1":
        data = np.ascontiguousarray(depth_m, dtype="<f4").tobytes()
        step = width * 4
    else:
        raise ValueError(f"unknown depth encoding {encoding!r}; expected '16UC1' or '32FC1'")
    return RawImage(
        timestamp=timestamp(stamp_ns), frame_id=frame_id, width=width, height=height,
        encoding=encoding, step=step, data=data,
    )


def point_cloud(
    stamp_ns: int, xyz: ArrayLike, rgb: ArrayLike | None, frame_id: str
) -> PointCloud:
    points = np.asarray(xyz, dtype=np.float32).reshape(-1, 3)
    n = points.shape[0]
    F = PackedElementField
    fields = [F(name="x", offset=0, type=F.FLOAT32), F(name="y", offset=4, type=F.FLOAT32),
              F(name="z", offset=8, type=F.FLOAT32)]
    if rgb is None:
        packed = np.ascontiguousarray(points, dtype="<f4")
        stride = 12
    else:
        colours = np.asarray(rgb, dtype=np.uint8).reshape(-1, 3)
        if colours.shape[0] != n:
            raise ValueError(f"{n} points but {colours.shape[0]} colours")
        dtype = np.dtype([("xyz", "<f4", 3), ("rgba", "u1", 4)])
        packed = np.empty(n, dtype=dtype)
        packed["xyz"] = points
        packed["rgba"][:, :3] = colours
        packed["rgba"][:, 3] = 255
        channels = ("red", "green", "blue", "alpha")
        fields += [F(name=c, offset=12 + i, type=F.UINT8) for i, c in enumerate(channels)]
        stride = 16
    return PointCloud(
        timestamp=timestamp(stamp_ns), frame_id=frame_id, pose=pose(np.eye(4)),
        point_stride=stride, fields=fields, data=packed.tobytes(),
    )


def color(rgba: RGBA) -> Color:
    r, g, b, a = (float(c) for c in rgba)
    return Color(r=r, g=g, b=b, a=a)


# Rotations taking an arrow's +x axis onto a pose's x, y and z axes.
_AXIS_ROTATIONS: tuple[tuple[NDArray[np.float64], RGBA], ...] = (
    (np.eye(3), (1.0, 0.1, 0.1, 1.0)),
    (np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]), (0.1, 0.9, 0.1, 1.0)),
    (np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]), (0.1, 0.3, 1.0, 1.0)),
)


def text_primitive(T: NDArray[np.float64], label: str, lift_m: float) -> TextPrimitive:
    M = T.copy()
    M[2, 3] += lift_m
    return TextPrimitive(pose=pose(M), billboard=True, font_size=14.0, scale_invariant=True,
                         color=color((1.0, 1.0, 1.0, 1.0)), text=label)


def box_entity(stamp_ns: int, marker: BoxMarker, frame_id: str) -> SceneEntity:
    M = as_matrix(marker.T_base_box)
    sx, sy, sz = (float(s) for s in marker.size_m)
    entity = SceneEntity(timestamp=timestamp(stamp_ns), frame_id=frame_id, id=marker.id)
    cube = CubePrimitive(pose=pose(M), size=Vector3(x=sx, y=sy, z=sz), color=color(marker.rgba))
    entity.cubes.append(cube)
    if marker.label:
        entity.texts.append(text_primitive(M, marker.label, 0.5 * sz + 0.02))
        entity.metadata.append(KeyValuePair(key="label", value=marker.label))
    return entity


def pose_entity(stamp_ns: int, marker: PoseMarker, frame_id: str) -> SceneEntity:
    M = as_matrix(marker.T_base_pose)
    length = float(marker.length_m)
    entity = SceneEntity(timestamp=timestamp(stamp_ns), frame_id=frame_id, id=marker.id)
    for i, (R_axis, rgba) in enumerate(_AXIS_ROTATIONS):
        A = M.copy()
        A[:3, :3] = M[:3, :3] @ R_axis
        entity.arrows.append(ArrowPrimitive(
            pose=pose(A), shaft_length=0.75 * length, shaft_diameter=0.06 * length,
            head_length=0.25 * length, head_diameter=0.15 * length,
            color=color(marker.rgba if i == 2 else rgba),
        ))
    if marker.label:
        entity.texts.append(text_primitive(M, marker.label, 0.02))
    for key, value in {"label": marker.label, **marker.metadata}.items():
        entity.metadata.append(KeyValuePair(key=key, value=str(value)))
    return entity


def image_annotations(stamp_ns: int, outlines: Sequence[tuple[NDArray[np.float64], str]],
                      rgba: RGBA = (0.16, 0.86, 1.0, 1.0)) -> ImageAnnotations:
    """Closed outlines (pixel polygons) with a label at each one's top-left corner."""
    ts = timestamp(stamp_ns)
    msg = ImageAnnotations()
    for polygon, label in outlines:
        points = [Point2(x=float(u), y=float(v)) for u, v in polygon]
        msg.points.append(PointsAnnotation(timestamp=ts, type=PointsAnnotation.LINE_LOOP, points=points,
                                           outline_color=color(rgba), thickness=2.0))
        if label:
            u0, v0 = float(min(p[0] for p in polygon)), float(min(p[1] for p in polygon))
            msg.texts.append(TextAnnotation(timestamp=ts, position=Point2(x=u0, y=max(v0 - 4.0, 0.0)), text=label,
                                            font_size=14.0, text_color=color(rgba),
                                            background_color=color((0.0, 0.0, 0.0, 0.6))))
    return msg


def scene_update(stamp_ns: int, entities: Sequence[SceneEntity]) -> SceneUpdate:
    """A SceneUpdate that replaces every entity previously shown on its topic."""
    deletion = SceneEntityDeletion(timestamp=timestamp(stamp_ns), type=SceneEntityDeletion.ALL)
    return SceneUpdate(deletions=[deletion], entities=list(entities))


_LOG_LEVELS: dict[str, Log.Level.ValueType] = {
    "DEBUG": Log.DEBUG, "INFO": Log.INFO, "WARNING": Log.WARNING, "WARN": Log.WARNING, "ERROR": Log.ERROR,
    "FATAL": Log.FATAL, "CRITICAL": Log.FATAL,
}


def log_level(level: str | int) -> Log.Level.ValueType:
    """A Foxglove log level (``Log.Level``) from a name ("INFO") or a ``logging`` level number (20)."""
    if isinstance(level, int):
        return _LOG_LEVELS["FATAL" if level >= 50 else "ERROR" if level >= 40 else "WARNING" if level >= 30
                           else "INFO" if level >= 20 else "DEBUG"]
    try:
        return _LOG_LEVELS[level.upper()]
    except KeyError:
        raise ValueError(f"unknown log level {level!r}; expected one of {sorted(_LOG_LEVELS)}") from None


def log(stamp_ns: int, level: str | int, name: str, message: str) -> Log:
    return Log(timestamp=timestamp(stamp_ns), level=log_level(level), message=message, name=name)
