"""Opening a camera source with its calibration: the camera, where its frames are, and the settings for its scene.

Every check that can refuse runs before the first frame: the calibration file (and, for a scene, that it fits the
scene's camera mount), an eye-in-hand calibration's tool poses (a recording's ``FILE.poses.jsonl``; a live wrist
camera has no arm to ask yet), and after opening, that the calibration was made with the source's intrinsics.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from bt_grasp.errors import InputError
from bt_grasp.hardware.realsense_settings import RealSenseSettings
from bt_grasp.hardware.tool_poses import ToolPose, poses_path, read_poses
from bt_grasp.interfaces import Camera, Mount
from bt_grasp.perception.calibration_file import CalibrationFile, calibration_for_scene, load_calibration
from bt_grasp.perception.config import PerceptionConfig
from bt_grasp.scene.format import Scene, load_scene
from bt_grasp.sensing.placement import FramePlacer
from bt_grasp.sensing.source_spec import SourceKind, SourceSpec


@dataclass
class OpenedSource:
    """An open source: ``camera`` (closed by :meth:`close`), ``placer``, the ``scene`` whose settings perception uses
    (the scene file's, or the default scene's for a camera: its workspace is the region of interest), and the
    default number of frames to perceive (None: every frame of a recording)."""

    spec: SourceSpec
    camera: Camera
    placer: FramePlacer
    scene: Scene
    perception_config: PerceptionConfig
    default_frames: int | None
    close: Callable[[], None]

    @property
    def calibrated(self) -> bool:
        return self.placer.calibration is not None


def _calibration(path: Path | None) -> CalibrationFile | None:
    return load_calibration(path) if path is not None else None


def open_source(spec: SourceSpec, calibration: Path | None, settings: RealSenseSettings = RealSenseSettings()
                ) -> OpenedSource:
    """Open ``spec`` (see the module docstring); InputError (exit 2) for anything that cannot be used."""
    if spec.kind is SourceKind.SCENE:
        return _open_scene(spec, calibration, settings)
    cal = _calibration(calibration)
    mount = Mount(cal.mount) if cal is not None else Mount.EYE_TO_HAND
    scene = Scene()
    tool_pose: Callable[[int], ToolPose | None] | None = None
    poses_name = ""
    if cal is not None and mount == Mount.EYE_IN_HAND:
        if spec.kind is SourceKind.DEVICE:
            raise InputError("--calibration", "is an eye-in-hand calibration: a live wrist camera's frames need the "
                             "arm's pose at each capture, which bt_grasp cannot read from a real arm yet; perceive "
                             "without --calibration (camera frame) or record with poses")
        assert spec.path is not None
        sidecar = poses_path(spec.path)
        if not sidecar.exists():
            raise InputError(spec.path, f"is perceived in the base frame with an eye-in-hand calibration, but no tool "
                             f"poses lie beside it ({sidecar.name}): a wrist camera's frames need the tool pose of "
                             "each")
        poses = read_poses(sidecar)
        tool_pose, poses_name = poses.get, str(sidecar)
    placer = FramePlacer(cal, calibration, tool_pose, poses_name)
    if spec.kind is SourceKind.RECORDING:
        # deferred: pyrealsense2 only when a RealSense source is asked for
        from bt_grasp.hardware.realsense_open import open_recording

        assert spec.path is not None
        camera = open_recording(spec.path, settings, mount)
        default_frames: int | None = None
    else:
        # deferred: pyrealsense2 only when a RealSense source is asked for
        from bt_grasp.hardware.realsense_open import open_device

        camera = open_device(spec.serial or None, settings, mount)
        default_frames = 1
    try:
        placer.check_source(camera.intrinsics)
    except InputError:
        camera.close()
        raise
    return OpenedSource(spec, camera, placer, scene, PerceptionConfig.for_scene(scene), default_frames, camera.close)


def _open_scene(spec: SourceSpec, calibration: Path | None, settings: RealSenseSettings) -> OpenedSource:
    # deferred: the simulator only when a scene is asked for
    from bt_grasp.sensing.scene_camera import SceneD435Camera

    assert spec.scene is not None
    scene = load_scene(spec.scene)
    if spec.mount is not None and spec.mount.value != scene.camera.mount:
        scene = scene.model_copy(update={"camera": scene.camera.model_copy(update={"mount": spec.mount.value})})
    cal_path, cal = calibration_for_scene(scene, spec.scene, calibration)
    camera = SceneD435Camera(spec.scene, spec.seed, spec.mount, settings)
    placer = FramePlacer(cal, cal_path, camera.tool_poses.get, f"the simulated arm of {spec.scene}")
    try:
        placer.check_source(camera.intrinsics)
    except InputError:
        camera.close()
        raise
    return OpenedSource(spec, camera, placer, camera.scene, PerceptionConfig.for_scene(camera.scene), 1,
                        camera.close)
