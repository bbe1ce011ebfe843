"""The hand-eye calibration file: written by ``bt-grasp calibrate``, read strictly by everything else.

Format (YAML, metres, quaternion w x y z)::

    version: 1
    mount: eye-to-hand              # or eye-in-hand
    parent_frame: base_link         # eye-to-hand: base_link; eye-in-hand: the tool link (tool0)
    child_frame: camera_color_optical_frame
    transform: {xyz_m: [..], quat_wxyz: [..], matrix: [[4 rows of 4]]}
    method: tsai+lm
    samples: 18
    residuals: {tsai: {residual_mm: .., residual_deg: .., scatter_mm: .., reprojection_px: ..}, ...}
    date: '2025-01-01T12:00:00+00:00'
    camera_intrinsics: {width_px: 640, height_px: 480, fx_px: .., fy_px: .., cx_px: .., cy_px: ..}
    board: {dictionary: DICT_5X5_100, squares_x: 5, squares_y: 7, square_m: 0.035, marker_m: 0.026}

``xyz_m`` + ``quat_wxyz`` and ``matrix`` must describe the same rigid transform (a hand-edited file where
they disagree is rejected). Any problem is a ConfigError naming the file and line.
"""

from __future__ import annotations

import datetime as _dt
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
import yaml
from pydantic import Field, model_validator

from bt_grasp.errors import ConfigError
from bt_grasp.files.config import StrictModel, read_yaml, validate
from bt_grasp.files.output_files import write_output_file
from bt_grasp.files.search_path import CALIBRATION_PATH_VARIABLE, SHIPPED_CALIBRATIONS, find_named_file, looked_in
from bt_grasp.geometry import Mat4, T_from_pos_quat_wxyz, T_from_xyz_rpy, quat_wxyz
from bt_grasp.interfaces import CameraIntrinsics, Mount
from bt_grasp.perception.charuco import BoardSpec
from bt_grasp.scene.format import Scene

Vec3 = tuple[float, float, float]
Row4 = tuple[float, float, float, float]


class TransformModel(StrictModel):
    xyz_m: Vec3
    quat_wxyz: Row4
    matrix: tuple[Row4, Row4, Row4, Row4]

    @model_validator(mode="after")
    def _consistent(self) -> TransformModel:
        q = np.asarray(self.quat_wxyz, dtype=float)
        if not np.all(np.isfinite(q)) or abs(np.linalg.norm(q) - 1.0) > 1e-3:
            raise ValueError("quat_wxyz must be a unit quaternion (w, x, y, z)")
        M = np.asarray(self.matrix, dtype=float)
        if not np.all(np.isfinite(M)) or not np.allclose(M[3], [0, 0, 0, 1]):
            raise ValueError("matrix must be a finite 4x4 homogeneous transform with last row [0, 0, 0, 1]")
        R = M[:3, :3]
        if not np.allclose(R.T @ R, np.eye(3), atol=1e-5) or np.linalg.det(R) < 0:
            raise ValueError("matrix's rotation part is not a rotation (orthonormal, determinant +1)")
        T = T_from_pos_quat_wxyz(list(self.xyz_m), q / np.linalg.norm(q))
        if not np.allclose(T, M, atol=1e-5):
            raise ValueError("xyz_m + quat_wxyz and matrix describe different transforms")
        return self

    @property
    def T(self) -> Mat4:
        return np.asarray(self.matrix, dtype=float)


class IntrinsicsModel(StrictModel):
    width_px: Annotated[int, Field(gt=0)]
    height_px: Annotated[int, Field(gt=0)]
    fx_px: Annotated[float, Field(gt=0)]
    fy_px: Annotated[float, Field(gt=0)]
    cx_px: float
    cy_px: float


class MethodResiduals(StrictModel):
    residual_mm: Annotated[float, Field(ge=0)]
    residual_deg: Annotated[float, Field(ge=0)]
    scatter_mm: Annotated[float, Field(ge=0)]
    reprojection_px: Annotated[float, Field(ge=0)]


class CalibrationFile(StrictModel):
    version: Literal[1] = 1
    mount: Literal["eye-to-hand", "eye-in-hand"]
    parent_frame: Annotated[str, Field(min_length=1)]
    child_frame: Annotated[str, Field(min_length=1)] = "camera_color_optical_frame"
    transform: TransformModel
    method: Annotated[str, Field(min_length=1)]
    samples: Annotated[int, Field(ge=3)]
    residuals: dict[str, MethodResiduals] = Field(default_factory=dict)
    date: str
    camera_intrinsics: IntrinsicsModel
    board: BoardSpec

    @property
    def T_parent_camera(self) -> Mat4:
        """``T_base_camera`` (eye-to-hand) or ``T_tool_camera`` (eye-in-hand, tool = ``parent_frame``)."""
        return self.transform.T

    @property
    def tool_link(self) -> str:
        """The link whose pose an eye-in-hand camera's pose is composed with (``tool0`` for eye-to-hand)."""
        return self.parent_frame if Mount(self.mount) == Mount.EYE_IN_HAND else "tool0"

    @property
    def T_base_camera(self) -> Mat4:
        """Eye-to-hand: the camera pose in the base frame. (Eye-in-hand: use :meth:`T_base_camera_at`.)"""
        if Mount(self.mount) != Mount.EYE_TO_HAND:
            raise ValueError("an eye-in-hand camera moves: use T_base_camera_at(T_base_tool) or T_tool_camera")
        return self.transform.T

    @property
    def T_tool_camera(self) -> Mat4:
        """Eye-in-hand: the camera pose in the ``tool_link`` frame."""
        if Mount(self.mount) != Mount.EYE_IN_HAND:
            raise ValueError("an eye-to-hand camera is not on the tool: use T_base_camera")
        return self.transform.T

    def T_base_camera_at(self, T_base_tool: Mat4 | None = None) -> Mat4:
        """The camera pose in the base frame at capture time (eye-in-hand needs ``T_base_tool`` then)."""
        if Mount(self.mount) == Mount.EYE_TO_HAND:
            return self.transform.T
        if T_base_tool is None:
            raise ValueError("an eye-in-hand calibration needs T_base_tool at capture time")
        return np.asarray(T_base_tool, dtype=float) @ self.transform.T

    @property
    def intrinsics(self) -> CameraIntrinsics:
        return CameraIntrinsics(**self.camera_intrinsics.model_dump())


def make_calibration(
    mount: str, T_parent_camera: Mat4, parent_frame: str, method: str, samples: int,
    residuals: dict[str, dict[str, float]], intrinsics: CameraIntrinsics, board: BoardSpec,
    date: str | None = None,
) -> CalibrationFile:
    T = np.asarray(T_parent_camera, dtype=float)
    q = quat_wxyz(T)
    if q[0] < 0:
        q = -q
    data = {
        "mount": mount,
        "parent_frame": parent_frame,
        "transform": {
            "xyz_m": [float(v) for v in T[:3, 3]],
            "quat_wxyz": [float(v) for v in q],
            "matrix": [[float(v) for v in row] for row in T],
        },
        "method": method,
        "samples": samples,
        "residuals": residuals,
        "date": date or _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "camera_intrinsics": intrinsics.to_dict(),
        "board": board.model_dump(),
    }
    return CalibrationFile.model_validate(data)


def save_calibration(calibration: CalibrationFile, path: str | Path) -> Path:
    """Write the file whole (parents created; ``bt_grasp.files.output_files``); returns its path."""
    data = calibration.model_dump(mode="json")
    header = (f"# bt_grasp hand-eye calibration ({calibration.mount}): maps camera_color_optical_frame "
              f"points into {calibration.parent_frame}\n")
    text = header + yaml.safe_dump(data, sort_keys=False, default_flow_style=None)
    return write_output_file(path, text, "--out", example="calibration.yaml")


def load_calibration(path: str | Path, mount: str | None = None, *, quote: bool = True) -> CalibrationFile:
    """Read and validate a calibration file; ConfigError (file:line: problem) on any problem, including a
    calibration made for another camera mount than ``mount`` (when given). ``quote=False``: the sentence quotes
    nothing of the file (a leaf reads the file a blackboard entry names, which a viewer may have set)."""
    expected_mount = mount
    data, lines = read_yaml(path)
    calibration = validate(CalibrationFile, data, path, lines, quote=quote)
    if expected_mount is not None and calibration.mount != expected_mount:
        raise ConfigError(
            path,
            f"this calibration is for an {calibration.mount} camera, but the camera is mounted {expected_mount}",
            where=lines.get(("mount",)),
        )
    return calibration


#: a calibration's intrinsics and the source's agree when every focal length and principal point is this close, px
INTRINSICS_TOLERANCE_PX = 0.01


def intrinsics_problem(calibration: CalibrationFile, source: CameraIntrinsics) -> str | None:
    """Why a calibration was not made with this source's colour intrinsics, or None."""
    cal = calibration.intrinsics
    if (cal.width_px, cal.height_px) != (source.width_px, source.height_px):
        return (f"it was made for a {cal.width_px}x{cal.height_px} picture, but the source's colour stream is "
                f"{source.width_px}x{source.height_px}")
    off = max(abs(a - b) for a, b in ((cal.fx_px, source.fx_px), (cal.fy_px, source.fy_px),
                                      (cal.cx_px, source.cx_px), (cal.cy_px, source.cy_px)))
    if off > INTRINSICS_TOLERANCE_PX:
        return (f"its intrinsics (fx {cal.fx_px:.2f}, fy {cal.fy_px:.2f}, cx {cal.cx_px:.2f}, cy {cal.cy_px:.2f} px) "
                f"are not the source's (fx {source.fx_px:.2f}, fy {source.fy_px:.2f}, cx {source.cx_px:.2f}, "
                f"cy {source.cy_px:.2f} px): it was made with another camera or resolution")
    return None


#: a calibration whose camera lies further than this from the scene's nominal mount was made for another pose
NOMINAL_POSITION_TOLERANCE_M = 0.03
NOMINAL_AXIS_TOLERANCE_DEG = 3.0


def mismatch_with_mount(calibration: CalibrationFile, scene: Scene) -> str | None:
    """Why a calibration cannot be for this scene's camera (another mount, or a camera pose more than a few
    cm or degrees from the scene's nominal mount), or None. The nominal mount is installation data."""
    camera = scene.camera
    if calibration.mount != camera.mount:
        return f"it is for an {calibration.mount} camera, but the scene's camera is mounted {camera.mount}"
    if Mount(camera.mount) == Mount.EYE_TO_HAND:
        T_base_world = np.linalg.inv(scene.T_world_base())
        position = (T_base_world @ [*camera.eye_to_hand.position_m, 1.0])[:3]
        axis = (T_base_world @ [*camera.eye_to_hand.look_at_m, 1.0])[:3] - position
        where = "base frame"
    else:
        T = T_from_xyz_rpy(np.array(camera.eye_in_hand.xyz_m), np.deg2rad(camera.eye_in_hand.rpy_deg))
        position, axis, where = T[:3, 3], T[:3, 2], f"{camera.eye_in_hand.parent_link} frame"
    T_cal = calibration.T_parent_camera
    off_m = float(np.linalg.norm(T_cal[:3, 3] - position))
    cos = float(np.dot(T_cal[:3, 2], axis) / (np.linalg.norm(axis) * np.linalg.norm(T_cal[:3, 2])))
    off_deg = float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
    if off_m > NOMINAL_POSITION_TOLERANCE_M or off_deg > NOMINAL_AXIS_TOLERANCE_DEG:
        return (f"it was made for another camera pose: {off_m * 100:.1f} cm and {off_deg:.1f} deg from the "
                f"scene's camera mount ({where}); calibrate again with `bt-grasp calibrate --scene SCENE --out FILE`")
    return None


#: how a command line gives a calibration of its own (``run``, ``eval run``, ``bench pick``)
CALIBRATION_OPTION = "pass --calibration FILE"


def calibration_for_scene(scene: Scene, scene_path: str | Path, override: str | Path | None,
                          *, give_one: str = CALIBRATION_OPTION) -> tuple[Path | None, CalibrationFile | None]:
    """The calibration a run uses: ``override`` (the ``--calibration`` flag) or the file the scene names, looked
    for beside the scene file, then in each folder of ``BT_GRASP_CALIBRATION_PATH``, then among the shipped scenes'
    calibrations (``bt_grasp/files/search_path.py``). Bad input (missing, unreadable, made for another mount or
    camera pose) is a ConfigError naming the file and line; no calibration at all is (None, None). ``give_one``:
    how the caller's user gives a calibration instead (a campaign file has a key for it, not a flag)."""
    if override is not None:
        path = Path(override)
        calibration = load_calibration(path, mount=scene.camera.mount)
        where: int | None = None
    elif scene.calibration:
        found = find_named_file(scene.calibration, Path(scene_path).parent, CALIBRATION_PATH_VARIABLE,
                                SHIPPED_CALIBRATIONS)
        where = read_yaml(scene_path)[1].get(("calibration",))
        if found.path is None:
            beside = Path(scene_path).parent / scene.calibration
            raise ConfigError(scene_path, f"the calibration file '{scene.calibration}' the scene names does not "
                              f"exist ({looked_in(found, CALIBRATION_PATH_VARIABLE)}); make it with `bt-grasp "
                              f"calibrate --scene {scene_path} --out {beside}` or {give_one}", where=where)
        path = found.path
        calibration = load_calibration(path, mount=scene.camera.mount)
    else:
        return None, None
    problem = mismatch_with_mount(calibration, scene)
    if problem:
        raise ConfigError(path, f"this calibration does not fit the scene {scene_path}: {problem}", where=where)
    return path, calibration
