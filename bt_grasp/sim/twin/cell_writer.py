"""``bt-grasp twin --write-cell FILE``: the cell file (``bt_grasp.cell.format``) of the cell a twin serves.

Everything is what an installation drawing of the twin's cell says, in the robot's base frame: the arm at the
twin's address with the gripper's TCP and mass as payload, the gripper model, the twin's camera, the scene's
calibration file, the table top as a plane, the fixtures as boxes, and the scene's work area (from the table top
to :data:`WORKSPACE_HEIGHT_M` above it) as the workspace box. The file is validated before it is written.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import yaml

from bt_grasp.cell.format import CELL_VERSION, Cell
from bt_grasp.files.output_files import write_output_file
from bt_grasp.geometry import inv
from bt_grasp.scene.format import Scene
from bt_grasp.sim.twin.config import GRIPPER_PORT, TwinConfig
from bt_grasp.sim.twin.gripper_models import GRIPPERS
from bt_grasp.sim.twin.motion import T_to_pose

#: how high above the table the workspace box reaches (m)
WORKSPACE_HEIGHT_M = 0.5


def _r(values: object, digits: int = 6) -> list[float]:
    return [round(float(v), digits) + 0.0 for v in values]  # type: ignore[attr-defined]


def cell_for(scene: Scene, scene_path: Path, config: TwinConfig, cell_path: Path) -> Cell:
    """The cell file's content for a twin of ``scene`` (validated)."""
    gripper = GRIPPERS[config.gripper]
    T_base_world = inv(scene.T_world_base())
    up = T_base_world[:3, :3] @ np.array([0.0, 0.0, 1.0])
    on_table = T_base_world @ np.array([0.0, 0.0, 0.0, 1.0])
    ws = scene.workspace
    corners = np.array([[x, y, z, 1.0] for x in ws.x_m for y in ws.y_m for z in (0.0, WORKSPACE_HEIGHT_M)])
    in_base = (T_base_world @ corners.T).T[:, :3]
    fixtures = []
    for fixture in scene.fixtures:
        boxes = [{"size_m": _r(part.size_m), "pose": _r(T_to_pose(T_base_world @ part.T_world_part)),
                  "solid": part.solid} for part in fixture.parts()]
        fixtures.append({"name": fixture.name, "kind": fixture.kind, "boxes": boxes})
    calibration = None
    if scene.calibration is not None:
        target = (scene_path.parent / scene.calibration).resolve()
        calibration = os.path.relpath(target, cell_path.resolve().parent)
    data = {
        "version": CELL_VERSION,
        "name": f"{scene.name}-twin",
        "arm": {"model": config.model.name, "address": config.host,
                "tcp_pose": [0.0, 0.0, gripper.tcp_z_m, 0.0, 0.0, 0.0], "payload_kg": gripper.mass_kg,
                "payload_cog_m": [0.0, 0.0, round(gripper.tcp_z_m / 2, 4)]},
        "gripper": {"model": gripper.name.value, "address": config.host, "port": GRIPPER_PORT,
                    "stroke_m": gripper.stroke_m, "pad_size_m": list(gripper.pad_size_m),
                    "tcp_to_fingertip_m": gripper.tcp_to_fingertip_m},
        "camera": {"kind": "twin", "model": scene.camera.model, "mount": scene.camera.mount,
                   "width_px": scene.camera.width_px, "height_px": scene.camera.height_px, "address": config.host},
        "calibration": calibration,
        "table_plane": {"normal": _r(up), "offset_m": round(float(up @ on_table[:3]), 6) + 0.0},
        "fixtures": fixtures,
        "workspace": {"min_m": _r(in_base.min(axis=0)), "max_m": _r(in_base.max(axis=0))},
    }
    return Cell.model_validate(data)


HEADER = """\
# The cell a bt-grasp twin serves (written by `bt-grasp twin --write-cell`; format: bt_grasp/cell/format.py).
# Base frame of the robot (base_link: x forward, z up), metres and radians; poses are [x, y, z, rx, ry, rz].
"""


def write_cell(scene: Scene, scene_path: Path, config: TwinConfig, cell_path: Path) -> Path:
    """Write the cell file (whole, or not at all: InputError naming ``--write-cell``)."""
    cell = cell_for(scene, scene_path, config, cell_path)
    text = HEADER + yaml.safe_dump(cell.model_dump(mode="json"), sort_keys=False, default_flow_style=None,
                                   width=110)
    return write_output_file(cell_path, text, "--write-cell", example="twin.cell.yaml")
