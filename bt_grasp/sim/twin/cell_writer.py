"""``bt-grasp twin --write-cell FILE``: the cell file (``bt_grasp.cell.format``) of the cell a twin serves.

Everything is what an installation drawing of the twin's cell says, in the robot's base frame: the arm at the
twin's address with the gripper's TCP and mass as payload and the scene's home pose, the gripper model, the twin's
camera with its nominal mounting, the scene's calibration file, the table top as a plane and its extent, the
fixtures (the scene's, placed in the base frame), the scene's work area (from the table top to
:data:`WORKSPACE_HEIGHT_M` above it) as the workspace box, and the calibration board when the twin mounted one
(``--board``). The file is validated before it is written.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from bt_grasp.cell.format import CELL_VERSION, Cell
from bt_grasp.cell.grippers import GRIPPERS, BoardLayout, GripperModel, GripperName, robot_urdf_path_with
from bt_grasp.errors import InputError
from bt_grasp.files.output_files import copy_output_file, write_output_file
from bt_grasp.files.search_path import CALIBRATION_PATH_VARIABLE, SHIPPED_CALIBRATIONS, find_named_file, looked_in
from bt_grasp.geometry import inv
from bt_grasp.scene.fixtures import Fixture
from bt_grasp.scene.format import Scene
from bt_grasp.sim.twin.config import GRIPPER_PORT, TwinConfig
from bt_grasp.sim.twin.motion import T_to_pose

#: how high above the table the workspace box reaches (m)
WORKSPACE_HEIGHT_M = 0.5


def _r(values: object, digits: int = 6) -> list[float]:
    return [round(float(v), digits) + 0.0 for v in values]  # type: ignore[attr-defined]


def _in_base(point_world: tuple[float, ...], T_base_world: np.ndarray) -> list[float]:
    return _r((T_base_world @ np.array([*point_world[:3], 1.0]))[:3])


def _fixture_in_base(fixture: Fixture, T_base_world: np.ndarray) -> dict[str, object]:
    """A scene fixture as the cell file has it: its footprint centre and yaw in the base frame (heights are
    from the table top in both)."""
    x, y = fixture.center_xy_m
    centre = T_base_world @ np.array([x, y, 0.0, 1.0])
    yaw = fixture.yaw_deg + float(np.degrees(np.arctan2(T_base_world[1, 0], T_base_world[0, 0])))
    moved = fixture.model_copy(update={"center_xy_m": (round(float(centre[0]), 6) + 0.0,
                                                        round(float(centre[1]), 6) + 0.0),
                                       "yaw_deg": round(yaw, 6) + 0.0})
    dumped: dict[str, object] = moved.model_dump(mode="json")
    return dumped


def home_for(scene: Scene, gripper: GripperModel) -> np.ndarray:
    """The home pose with ``gripper``: the scene's home with bt_grasp's own gripper puts the TCP where every scene
    keeps it out of the camera's objects (above the workspace's height); a longer gripper's home puts its TCP
    there too (the wrist stands higher), the solution nearest the scene's home."""
    from bt_grasp.motion.kinematics import ArmKinematics, default_kinematics  # deferred: pinocchio, once

    q_home = np.asarray(scene.robot.home_q_rad, dtype=float)
    if gripper.name == GripperName.BT_GRASP:
        return q_home
    T_tcp = default_kinematics().fk(q_home)
    found = ArmKinematics(urdf_path=robot_urdf_path_with(gripper.name)).ik(T_tcp, q_home)
    if not found.ok:
        raise ValueError(f"the scene's home TCP is out of reach with the {gripper.name.value}")
    return np.asarray(found.q, dtype=float)


def cell_for(scene: Scene, scene_path: Path, config: TwinConfig, cell_path: Path,
             board: tuple[BoardLayout, np.ndarray] | None = None) -> Cell:
    """The cell file's content for a twin of ``scene`` (validated); ``board``: the calibration board the twin
    mounted on its gripper (layout and ``T_tool_board``)."""
    gripper = GRIPPERS[config.gripper]
    T_base_world = inv(scene.T_world_base())
    up = T_base_world[:3, :3] @ np.array([0.0, 0.0, 1.0])
    on_table = T_base_world @ np.array([0.0, 0.0, 0.0, 1.0])
    ws = scene.workspace
    corners = np.array([[x, y, z, 1.0] for x in ws.x_m for y in ws.y_m for z in (0.0, WORKSPACE_HEIGHT_M)])
    in_base = (T_base_world @ corners.T).T[:, :3]
    table = scene.table
    tx, ty = table.center_xy_m
    table_corners = np.array([[tx + sx * table.size_m[0] / 2, ty + sy * table.size_m[1] / 2, 0.0, 1.0]
                              for sx in (-1, 1) for sy in (-1, 1)])
    table_in_base = (T_base_world @ table_corners.T).T[:, :3]
    # a calibration file of the cell's own, beside the cell file (write_cell copies the scene's there): never the
    # scene's, which `calibrate --cell` would overwrite (the shipped scenes' link into bt_grasp's own files)
    calibration = None if scene.calibration is None else calibration_file_of(cell_path).name
    cam = scene.camera
    e2h = cam.eye_to_hand
    eih = cam.eye_in_hand
    data = {
        "version": CELL_VERSION,
        "name": f"{scene.name}-twin",
        "arm": {"model": config.model.name, "address": config.host,
                "tcp_pose": [0.0, 0.0, gripper.tcp_z_m, 0.0, 0.0, 0.0], "payload_kg": gripper.mass_kg,
                "payload_cog_m": [0.0, 0.0, round(gripper.tcp_z_m / 2, 4)],
                "home_q_rad": _r(home_for(scene, gripper))},
        "gripper": {"model": gripper.name.value, "address": config.host, "port": GRIPPER_PORT,
                    "stroke_m": gripper.stroke_m, "pad_size_m": list(gripper.pad_size_m),
                    "tcp_to_fingertip_m": gripper.tcp_to_fingertip_m},
        "camera": {"kind": "twin", "model": cam.model, "mount": cam.mount, "width_px": cam.width_px,
                   "height_px": cam.height_px, "address": config.host, "port": config.camera_port,
                   "eye_to_hand": {"position_m": _in_base(e2h.position_m, T_base_world),
                                   "look_at_m": _in_base(e2h.look_at_m, T_base_world), "roll_deg": e2h.roll_deg},
                   "eye_in_hand": {"parent_link": eih.parent_link, "xyz_m": list(eih.xyz_m),
                                   "rpy_deg": list(eih.rpy_deg)}},
        "calibration": calibration,
        "table_plane": {"normal": _r(up), "offset_m": round(float(up @ on_table[:3]), 6) + 0.0,
                        "x_m": _r([table_in_base[:, 0].min(), table_in_base[:, 0].max()]),
                        "y_m": _r([table_in_base[:, 1].min(), table_in_base[:, 1].max()])},
        "fixtures": [_fixture_in_base(f, T_base_world) for f in scene.fixtures],
        "workspace": {"min_m": _r(in_base.min(axis=0)), "max_m": _r(in_base.max(axis=0)),
                      "objects_up_to_m": ws.z_max_m},
        "board": None if board is None else {**board[0].as_dict(), "pose": _r(T_to_pose(board[1]))},
    }
    return Cell.model_validate(data)


HEADER = """\
# The cell a bt-grasp twin serves (written by `bt-grasp twin --write-cell`; format: bt_grasp/cell/format.py).
# Base frame of the robot (base_link: x forward, z up), metres and radians; poses are [x, y, z, rx, ry, rz].
"""


def calibration_file_of(cell_path: Path) -> Path:
    """The calibration file a twin's cell file names: ``NAME.calibration.yaml`` beside ``NAME.yaml``."""
    stem = cell_path.name.removesuffix(".yaml").removesuffix(".yml")
    return cell_path.parent / f"{stem}.calibration.yaml"


def write_cell(scene: Scene, scene_path: Path, config: TwinConfig, cell_path: Path,
               board: tuple[BoardLayout, np.ndarray] | None = None) -> Path:
    """Write the cell file (whole, or not at all: InputError naming ``--write-cell``) and, when the scene names a
    calibration, a copy of it as the cell's own (:func:`calibration_file_of`; the twin's camera is the scene's, so
    the scene's calibration holds until ``calibrate --cell`` replaces the copy)."""
    cell = cell_for(scene, scene_path, config, cell_path, board)
    if scene.calibration is not None:
        found = find_named_file(scene.calibration, scene_path.parent, CALIBRATION_PATH_VARIABLE,
                                SHIPPED_CALIBRATIONS)
        if found.path is None:
            raise InputError(scene_path, f"the calibration file '{scene.calibration}' the scene names does not exist "
                             f"({looked_in(found, CALIBRATION_PATH_VARIABLE)})")
        copy_output_file(found.path, calibration_file_of(cell_path), "--write-cell", example="twin.cell.yaml")
    text = HEADER + yaml.safe_dump(cell.model_dump(mode="json"), sort_keys=False, default_flow_style=None,
                                   width=110)
    return write_output_file(cell_path, text, "--write-cell", example="twin.cell.yaml")
