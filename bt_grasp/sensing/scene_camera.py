"""The simulated cell's D435, read as a live RealSense device through pyrealsense2.

``perceive --scene S --seed N`` and ``camera record --scene S --seed N`` draw the same frames
(:func:`simulated_d435`): the world built from the scene and the seed, 0.1 s of settling (as ``scene render``), an
eye-in-hand camera's arm at the survey view a tree's ``LookAt view="workspace"`` takes (computed from the scene's
nominal camera mount), then one frame per frame period. ``camera record`` feeds them to pyrealsense2's recorder;
:class:`SceneD435Camera` feeds them to a software device added to a pyrealsense2 context and reads them back through
the pipeline, the filters and ``rs.align`` -- the code that reads a live D435 -- so the same frame recorded and read
from the file gives the same depth, bit for bit.
"""

from __future__ import annotations

import dataclasses
import logging
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.geometry import T_from_xyz_rpy, inv
from bt_grasp.hardware.realsense_camera import PLAYBACK_TIMEOUT_MS, RealSenseCamera
from bt_grasp.hardware.realsense_settings import RealSenseSettings
from bt_grasp.hardware.software_d435 import D435Streams, SoftwareD435
from bt_grasp.hardware.tool_poses import ToolPose
from bt_grasp.interfaces import CameraIntrinsics, Mount, RGBDFrame
from bt_grasp.robot_description import BASE_LINK
from bt_grasp.scene.format import Scene, load_scene

if TYPE_CHECKING:  # the simulator is imported when a scene is asked for, never to parse a command line
    from bt_grasp.sim.simulated_d435 import D435Frame, SimulatedD435

log = logging.getLogger(__name__)

#: the serial number the simulated D435 reports
SIMULATED_SERIAL = "000000000435"
#: control periods of settling before the first frame (``scene render`` waits as long)
SETTLE_TICKS = 10


def survey_joints(scene: Scene) -> NDArray[np.float64]:
    """The arm's joints at the survey view of an eye-in-hand camera (``LookAt view="workspace"``), from home, with
    the scene's nominal camera mount (installation data). ValueError when out of reach (a scene file's mistake)."""
    # deferred: the leaves' package (py_trees) only when a tree or its view geometry is needed
    from bt_grasp.behaviours.viewing import SURVEY_DISTANCE_M, SURVEY_PULL_M, tool_pose_for_view

    # deferred: pinocchio and OMPL only when grasps are tested for reach or planned
    from bt_grasp.motion.kinematics import default_kinematics

    mount = scene.camera.eye_in_hand
    T_tool_camera = T_from_xyz_rpy(np.array(mount.xyz_m), np.deg2rad(mount.rpy_deg))
    ws = scene.workspace
    centre = (inv(scene.T_world_base()) @ np.array([np.mean(ws.x_m), np.mean(ws.y_m), 0.0, 1.0]))[:3]
    centre[:2] -= SURVEY_PULL_M * centre[:2] / max(float(np.linalg.norm(centre[:2])), 1e-9)
    kin = default_kinematics()
    q_home = np.asarray(scene.robot.home_q_rad, dtype=np.float64)
    T_tool_tcp = inv(kin.fk_link(q_home, mount.parent_link)) @ kin.fk(q_home)
    found = kin.ik(tool_pose_for_view(centre, SURVEY_DISTANCE_M, T_tool_camera) @ T_tool_tcp, q_home)
    if not found.ok:
        raise ValueError("the survey view of the workspace is out of the arm's reach")
    return np.asarray(found.q, dtype=np.float64)


def tool_pose(scene: Scene, q_rad: NDArray[np.float64], stamp_ns: int) -> ToolPose:
    """The eye-in-hand camera's parent link in the base frame at joints ``q_rad`` (the arm's forward kinematics,
    as a real controller reports it)."""
    # deferred: pinocchio and OMPL only when grasps are tested for reach or planned
    from bt_grasp.motion.kinematics import default_kinematics

    link = scene.camera.eye_in_hand.parent_link
    T = np.asarray(default_kinematics().fk_link(np.asarray(q_rad, dtype=float), link), dtype=float)
    return ToolPose(stamp_ns, T, BASE_LINK, link)


def simulated_d435(scene_path: str | Path, seed: int, mount: Mount | None = None,
                   config: Scene | None = None) -> SimulatedD435:
    """The simulated cell's two imagers, ready for the first frame (see the module docstring); ``config``: the
    scene already loaded from ``scene_path`` (else it is loaded). Imports the simulator."""
    # deferred: the simulator (sapien) only when a scene is asked for
    from bt_grasp.sim.simulated_d435 import SimulatedD435

    # deferred: the simulator (sapien) only when a scene is asked for
    from bt_grasp.sim.world import World

    config = config if config is not None else load_scene(scene_path)
    world = World(config, seed, camera_mount=mount, source=scene_path)
    if world.camera_mount == Mount.EYE_IN_HAND:
        world.robot.reset(survey_joints(world.config))
    world.step(world.steps_per_tick * SETTLE_TICKS)
    return SimulatedD435(world)


def streams_of(sim: SimulatedD435, serial: str = SIMULATED_SERIAL) -> D435Streams:
    """The software device's streams for the simulated D435."""
    # deferred: the simulator (sapien) only when a scene is asked for
    from bt_grasp.sim.simulated_d435 import FPS

    color: CameraIntrinsics = sim.world.camera.intrinsics
    return D435Streams(color=color, depth=sim.model.intrinsics, T_color_depth=sim.model.T_color_depth, fps=FPS,
                       serial=serial)


class SceneD435Camera:
    """Implements :class:`bt_grasp.interfaces.Camera`: the simulated D435 read as a live device (module docstring).

    ``tool_poses``: the eye-in-hand tool pose of every frame captured, by stamp; ``last``: the simulator's frame
    behind the last capture (for comparisons)."""

    def __init__(self, scene_path: str | Path, seed: int, mount: Mount | None = None,
                 settings: RealSenseSettings = RealSenseSettings()) -> None:
        # deferred: pyrealsense2 only when a RealSense source is asked for
        from bt_grasp.hardware.realsense_lib import pyrealsense2

        # deferred: pyrealsense2 only when a RealSense source is asked for
        from bt_grasp.hardware.realsense_open import open_device

        # deferred: the simulator (sapien) only when a scene is asked for
        from bt_grasp.sim.simulated_d435 import FPS

        rs = pyrealsense2("--scene (the simulated D435 is read through pyrealsense2)")
        self.scene = load_scene(scene_path)
        self.sim = simulated_d435(scene_path, seed, mount, self.scene)
        self.scene = self.sim.world.config  # the objects drawn for this seed
        streams = streams_of(self.sim)
        self.device = SoftwareD435(streams)
        self._context = rs.context()
        self.device.add_to(self._context)
        c = streams.color
        # no auto exposure to settle; and each frame is pushed before it is waited for, so it always comes: the wall
        # clock may not decide a simulated run's outcome, and the timeout only guards against a stuck library
        timeout_ms = max(settings.timeout_ms, PLAYBACK_TIMEOUT_MS)
        live = dataclasses.replace(settings, width_px=c.width_px, height_px=c.height_px, fps=FPS, settle_frames=0,
                                   timeout_ms=timeout_ms)
        self.camera: RealSenseCamera = open_device(SIMULATED_SERIAL, live, self.sim.world.camera_mount,
                                                   self._context)
        self.tool_poses: dict[int, ToolPose] = {}
        self.last: D435Frame | None = None
        self._started = False

    @property
    def intrinsics(self) -> CameraIntrinsics:
        return self.camera.intrinsics

    @property
    def mount(self) -> Mount:
        return self.camera.mount

    def capture(self) -> RGBDFrame | None:
        if self._started:
            self.sim.next_frame()
        self._started = True
        raw = self.sim.capture()
        self.last = raw
        if self.mount == Mount.EYE_IN_HAND:
            self.tool_poses[raw.stamp_ns] = tool_pose(self.scene, raw.q_rad, raw.stamp_ns)
        self.device.push(raw.depth_m, raw.color, raw.stamp_ns, raw.number)
        return self.camera.capture()

    def close(self) -> None:
        """Stop the pipeline, then let go of the software device before its context, the context's notification
        first (pyrealsense2 calls it from its own thread: it must not outlive what it reaches)."""
        self.camera.close()
        self.device.release(self._context)
