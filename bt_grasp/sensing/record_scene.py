"""``camera record``: recordings written by pyrealsense2's own recorder, from the simulator or from a live device.

From a scene: the simulated D435's frames (``bt_grasp.sensing.scene_camera.simulated_d435``: the frames
``perceive --scene`` reads) pushed into a software D435 whose recorder writes the ``.db3``; an eye-in-hand camera's
tool pose of every frame goes beside it (``FILE.poses.jsonl``). The recording is written under a temporary name in
the same folder and renamed when complete, so an interrupted command leaves no half-written recording behind.
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from bt_grasp.errors import InputError
from bt_grasp.hardware.tool_poses import ToolPose, poses_path, write_poses
from bt_grasp.interfaces import Mount

if TYPE_CHECKING:
    from bt_grasp.scene.format import Scene
    from bt_grasp.sim.simulated_d435 import D435Frame

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SceneRecording:
    path: Path
    poses: Path | None  # the eye-in-hand tool poses beside it
    frames: int
    mount: Mount
    first_stamp_ns: int
    last_stamp_ns: int


def check_recording_output(out: str | Path) -> Path:
    """``--out``: a ``.db3`` path bt_grasp may write (pyrealsense2 2.59's recorder writes no other format)."""
    # deferred: written only when a recording is complete
    from bt_grasp.files.output_files import check_output_file

    out = Path(out)
    if out.suffix != ".db3":
        raise InputError(out, "a recording is written as .db3 (pyrealsense2 2.59's recorder writes only the ROS 2 "
                         "format); name the file FILE.db3")
    check_output_file(out, "--out", example="recording.db3")
    return out


def record_scene(scene: str | Path, seed: int, out: str | Path, frames: int = 1, mount: Mount | None = None, *,
                 config: Scene | None = None, on_frame: Callable[[D435Frame], None] | None = None) -> SceneRecording:
    """Record ``frames`` frames of the scene's simulated D435 into ``out`` (see the module docstring). ``config``:
    the scene already loaded (or changed: a comparison without the noise model); ``on_frame``: sees each frame
    recorded."""
    # deferred: pyrealsense2 only when a RealSense source is asked for
    from bt_grasp.hardware.realsense_lib import pyrealsense2

    # deferred: pyrealsense2 only when a RealSense source is asked for
    from bt_grasp.hardware.software_d435 import SoftwareD435

    # deferred: the simulator only when a scene is asked for
    from bt_grasp.sensing.scene_camera import simulated_d435, streams_of, tool_pose

    if frames < 1:
        raise InputError("--frames", f"a recording holds at least one frame, not {frames}")
    out = check_recording_output(out)
    pyrealsense2("writing a RealSense recording")  # before the simulator is built
    sim = simulated_d435(scene, seed, mount, config)
    actual_mount = sim.world.camera_mount
    partial = out.with_name(f".{out.stem}.partial.db3")
    with contextlib.suppress(FileNotFoundError):
        partial.unlink()
    device = SoftwareD435(streams_of(sim))
    poses: list[ToolPose] = []
    stamps: list[int] = []
    try:
        device.record(partial)
        for k in range(frames):
            if k:
                sim.next_frame()
            raw = sim.capture()
            if actual_mount == Mount.EYE_IN_HAND:
                poses.append(tool_pose(sim.world.config, raw.q_rad, raw.stamp_ns))
            device.push(raw.depth_m, raw.color, raw.stamp_ns, raw.number)
            stamps.append(raw.stamp_ns)
            if on_frame is not None:
                on_frame(raw)
        device.close()  # the recorder finishes the file when released
        del device
        os.replace(partial, out)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            partial.unlink()
        raise
    sidecar = poses_path(out)
    if poses:
        write_poses(sidecar, poses)
    else:
        with contextlib.suppress(FileNotFoundError):
            sidecar.unlink()  # a wrist camera's poses of a recording this one replaced
    log.info("recorded %d frames of %s seed %d into %s", frames, scene, seed, out)
    return SceneRecording(out, sidecar if poses else None, frames, actual_mount, stamps[0], stamps[-1])
