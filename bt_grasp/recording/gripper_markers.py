"""Ranked grasps drawn as the gripper that would make them (a ``foxglove.SceneUpdate`` for ``/perception/grasps``).

Each grasp is one entity: the two finger pads opened to the grasp's width plus the pads' play, the palm joining them,
and a stem up the approach line to the pre-grasp pose, in the tcp frame bt_grasp's grasps use (z: approach, down
towards the object; y: the closing direction; the finger tips ``TCP_TO_FINGERTIP_M`` below the tcp). The best grasp
is drawn solid green, the next ones fading blue, each labelled with its rank, object and score.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from foxglove_schemas_protobuf.CubePrimitive_pb2 import CubePrimitive
from foxglove_schemas_protobuf.KeyValuePair_pb2 import KeyValuePair
from foxglove_schemas_protobuf.SceneEntity_pb2 import SceneEntity
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from foxglove_schemas_protobuf.Vector3_pb2 import Vector3
from numpy.typing import ArrayLike

from bt_grasp.recording import schemas
from bt_grasp.robot_description import TCP_TO_FINGERTIP_M

#: pad and palm sizes drawn, m (the project gripper's: 20 mm deep, 12 mm thick pads; a 10 mm palm 40 mm above the tcp)
PAD_DEPTH_M, PAD_THICKNESS_M = 0.020, 0.012
PALM_ABOVE_TCP_M, PALM_THICKNESS_M = 0.040, 0.010
STEM_WIDTH_M = 0.006
BEST_RGBA = (0.15, 0.85, 0.25, 0.95)
OTHER_RGBA = (0.20, 0.45, 1.00, 0.55)


@dataclass(frozen=True)
class GripperMarker:
    """One grasp to draw: ``T_frame_tcp`` its pose, ``width_m`` the object's width between the pads,
    ``approach_m`` the stem's length (the pre-grasp's distance above the grasp), ``rank`` 0 = best."""

    id: str
    T_frame_tcp: ArrayLike
    width_m: float
    approach_m: float
    rank: int
    label: str = ""


def _cube(T_frame_tcp: np.ndarray, centre: tuple[float, float, float], size: tuple[float, float, float],
          rgba: tuple[float, float, float, float]) -> CubePrimitive:
    T = np.eye(4)
    T[:3, 3] = centre
    M = T_frame_tcp @ T
    return CubePrimitive(pose=schemas.pose(M), size=Vector3(x=size[0], y=size[1], z=size[2]),
                         color=schemas.color(rgba))


def gripper_entity(stamp_ns: int, marker: GripperMarker, frame_id: str) -> SceneEntity:
    """The gripper of one grasp as cubes (see the module docstring)."""
    T = schemas.as_matrix(marker.T_frame_tcp)
    rgba = BEST_RGBA if marker.rank == 0 else (*OTHER_RGBA[:3], max(0.2, OTHER_RGBA[3] - 0.08 * marker.rank))
    half = 0.5 * float(marker.width_m) + 0.5 * PAD_THICKNESS_M + 0.005  # the open pads' play
    finger_len = TCP_TO_FINGERTIP_M + PALM_ABOVE_TCP_M
    finger_z = 0.5 * (TCP_TO_FINGERTIP_M - PALM_ABOVE_TCP_M)
    entity = SceneEntity(timestamp=schemas.timestamp(stamp_ns), frame_id=frame_id, id=marker.id)
    for side in (-1.0, 1.0):
        entity.cubes.append(_cube(T, (0.0, side * half, finger_z), (PAD_DEPTH_M, PAD_THICKNESS_M, finger_len), rgba))
    palm_width = 2 * half + PAD_THICKNESS_M
    entity.cubes.append(_cube(T, (0.0, 0.0, -PALM_ABOVE_TCP_M), (PAD_DEPTH_M, palm_width, PALM_THICKNESS_M), rgba))
    stem = max(float(marker.approach_m), 0.01)
    entity.cubes.append(_cube(T, (0.0, 0.0, -PALM_ABOVE_TCP_M - 0.5 * stem), (STEM_WIDTH_M, STEM_WIDTH_M, stem),
                              rgba))
    if marker.label:
        entity.texts.append(schemas.text_primitive(T, marker.label, 0.06))
        entity.metadata.append(KeyValuePair(key="label", value=marker.label))
    entity.metadata.append(KeyValuePair(key="rank", value=str(marker.rank)))
    return entity


def gripper_update(stamp_ns: int, markers: Sequence[GripperMarker], frame_id: str) -> SceneUpdate:
    """A SceneUpdate replacing every grasp drawn before with these."""
    return schemas.scene_update(stamp_ns, [gripper_entity(stamp_ns, m, frame_id) for m in markers])
