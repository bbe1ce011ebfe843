"""The twin's camera, rendered in a process of its own so that rendering never holds up the controller's cycle.

SAPIEN's renderer takes ~25-45 ms a frame on a CPU (lavapipe) and holds the Python interpreter while it reads a
picture back; the controller's cycle is 8 ms. So a second process builds the same world (same scene file, seed
and gripper: the same objects in the same places) without ever stepping its physics, and renders what the
controller's world looks like now: the main process sends the arm's joint positions and every object's pose,
the worker poses its copy, renders colour + depth (with the scene's seeded noise model, as ``SimCamera.capture``
does) into shared memory and answers with a short message. The worker runs at a lower scheduling priority
(``nice`` +10), so on a busy machine the controller's cycle wins.

:meth:`TwinCamera.capture` returns an :class:`bt_grasp.interfaces.RGBDFrame` (colour and depth aligned to colour, as
``SimCamera`` gives a simulated run); :meth:`TwinCamera.capture_d435` returns what a D435 delivers instead, the colour
picture and the **depth imager's own** picture (``bt_grasp.sim.depth_imager``, its noise from a stream of its own),
which the camera port (``bt_grasp.sim.twin.camera_port``) hands to a run; the run feeds them into a pyrealsense2
software device and aligns them with the library's ``rs.align``, as it does a real D435's. With the calibration
board mounted (``TwinConfig.board``) the render process mounts it too, so the camera sees it.
"""

from __future__ import annotations

import contextlib
import logging
import multiprocessing as mp
import os
import threading
import time
from dataclasses import dataclass
from multiprocessing.connection import Connection
from multiprocessing.process import BaseProcess
from multiprocessing.shared_memory import SharedMemory

import numpy as np
from numpy.typing import NDArray

from bt_grasp.interfaces import CameraIntrinsics, Mount, RGBDFrame
from bt_grasp.seeds import RunSeeds, Stream

log = logging.getLogger(__name__)

#: how long the first frame may take (the worker builds its world and warms the renderer first)
START_TIMEOUT_S = 60.0
FRAME_TIMEOUT_S = 10.0
WORKER_NICE = 10


@dataclass(frozen=True)
class PoseSnapshot:
    """What the camera must show: every articulation joint position and each object's pose (p + wxyz q)."""

    qpos: tuple[float, ...]
    object_poses: tuple[tuple[float, ...], ...]
    stamp_ns: int


@dataclass(frozen=True)
class D435Pair:
    """One frame as a D435 delivers it: the colour picture and the depth imager's own picture (m, 0 = invalid)."""

    color: NDArray[np.uint8]
    depth_m: NDArray[np.float32]
    stamp_ns: int


@dataclass(frozen=True)
class FrameStats:
    frames: int
    last_render_ms: float
    mean_render_ms: float


def _worker(conn: Connection, scene_path: str, seed: int, gripper: str, shm_name: str,
            board: tuple[dict[str, str | int | float], list[list[float]]] | None = None) -> None:
    """The render process: build the world, then pose + render on request until told to stop. A request is a
    :class:`PoseSnapshot` and whether the depth imager's picture is wanted too."""
    import signal  # deferred: the render process's own set-up, in the child only

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C reaches the whole process group: the twin stops us
    with contextlib.suppress(OSError):
        os.nice(WORKER_NICE)

    import sapien

    from bt_grasp.scene.format import load_scene  # deferred: as above, in the render process only
    from bt_grasp.sim.depth_imager import DepthImager, DepthImagerModel  # deferred: as above
    from bt_grasp.sim.render_keeper import keep_renderer_warm  # deferred: as above
    from bt_grasp.sim.world import World  # deferred: as above

    keep_renderer_warm()
    from bt_grasp.cell.grippers import GripperName, robot_urdf_path_with  # deferred: as above

    # the robot description is made here: the twin's is a sealed in-memory file of the twin's process, which a
    # spawned process cannot open
    name = GripperName(gripper)
    world = World(load_scene(scene_path), seed, source=scene_path,
                  robot_urdf=None if name == GripperName.BT_GRASP else robot_urdf_path_with(name))
    if board is not None:
        from bt_grasp.perception.charuco import BoardSpec  # deferred: as above
        from bt_grasp.sim.charuco import attach_board_to_link  # deferred: as above

        attach_board_to_link(world, BoardSpec.model_validate(board[0]), "gripper_palm", np.array(board[1], dtype=float))

    shm = SharedMemory(name=shm_name)
    camera = world.camera
    h, w = camera.intrinsics.height_px, camera.intrinsics.width_px
    color_out = np.ndarray((h, w, 3), dtype=np.uint8, buffer=shm.buf)
    depth_out = np.ndarray((h, w), dtype=np.float32, buffer=shm.buf, offset=h * w * 3)
    imager_out = np.ndarray((h, w), dtype=np.float32, buffer=shm.buf, offset=h * w * 7)
    cam = world.config.camera
    rng = RunSeeds(seed).generator(Stream.DEPTH_IMAGER)  # the simulated D435's stream, as a simulated run draws
    imager = DepthImager(camera, DepthImagerModel.d435(w, h), cam.noise, rng, cam.near_m, cam.far_m)
    entities = list(world.objects.values())
    camera.capture()  # the first picture pays the renderer's set-up
    conn.send(("ready", 0.0))
    try:
        while True:
            message = conn.recv()
            if message is None:
                break
            snapshot, with_imager = message
            start = time.perf_counter()
            world.robot.articulation.set_qpos(np.asarray(snapshot.qpos, dtype=np.float32))
            for entity, pose in zip(entities, snapshot.object_poses, strict=True):
                entity.set_pose(sapien.Pose(p=list(pose[:3]), q=list(pose[3:])))
            frame = camera.capture()
            assert frame is not None
            color_out[...] = frame.color
            depth_out[...] = frame.depth_m
            if with_imager:
                imager_out[...] = imager.capture()
            conn.send(("frame", (time.perf_counter() - start) * 1000.0))
    finally:
        del color_out, depth_out, imager_out
        shm.close()


class TwinCamera:
    """The render process's handle in the twin: :meth:`capture` a frame of a :class:`PoseSnapshot`."""

    def __init__(self, scene_path: str, seed: int, gripper: str, intrinsics: CameraIntrinsics,
                 mount: Mount, board: tuple[dict[str, str | int | float], list[list[float]]] | None = None) -> None:
        """``gripper``: the :class:`~bt_grasp.cell.grippers.GripperName` whose robot description the render process
        builds its world with."""
        self.intrinsics = intrinsics
        self.mount = mount
        self._args = (scene_path, seed, gripper)
        self._board = board
        self._shm: SharedMemory | None = None
        self._process: BaseProcess | None = None
        self._conn: Connection | None = None
        self._lock = threading.Lock()
        self._ready = False
        self.frames = 0
        self.render_ms: list[float] = []

    def start(self) -> None:
        """Start the render process (it builds its world meanwhile; the first :meth:`capture` waits for it)."""
        h, w = self.intrinsics.height_px, self.intrinsics.width_px
        self._shm = SharedMemory(create=True, size=h * w * 3 + 2 * h * w * 4)
        ctx = mp.get_context("spawn")
        self._conn, child = ctx.Pipe()
        self._process = ctx.Process(target=_worker, args=(child, *self._args, self._shm.name, self._board),
                                    name="twin-camera", daemon=True)
        self._process.start()
        child.close()

    def _parts(self) -> tuple[Connection, SharedMemory]:
        if self._conn is None or self._shm is None:
            raise RuntimeError("the twin's camera was not started")
        return self._conn, self._shm

    def _await_ready(self, conn: Connection) -> None:
        if self._ready:
            return
        if not conn.poll(START_TIMEOUT_S):
            raise TimeoutError(f"the twin's camera process did not start within {START_TIMEOUT_S:g} s")
        kind, _ = conn.recv()
        self._ready = kind == "ready"

    def _render(self, snapshot: PoseSnapshot, with_imager: bool) -> tuple[NDArray[np.uint8], NDArray[np.float32],
                                                                             NDArray[np.float32] | None]:
        conn, shm = self._parts()
        with self._lock:
            self._await_ready(conn)
            conn.send((snapshot, with_imager))
            if not conn.poll(FRAME_TIMEOUT_S):
                raise TimeoutError(f"the twin's camera rendered no frame within {FRAME_TIMEOUT_S:g} s")
            _, render_ms = conn.recv()
            h, w = self.intrinsics.height_px, self.intrinsics.width_px
            color = np.ndarray((h, w, 3), dtype=np.uint8, buffer=shm.buf).copy()
            depth = np.ndarray((h, w), dtype=np.float32, buffer=shm.buf, offset=h * w * 3).copy()
            imager = (np.ndarray((h, w), dtype=np.float32, buffer=shm.buf, offset=h * w * 7).copy()
                      if with_imager else None)
            self.frames += 1
            self.render_ms.append(float(render_ms))
            del self.render_ms[:-256]
        return color, depth, imager

    def capture(self, snapshot: PoseSnapshot) -> RGBDFrame:
        """Render ``snapshot`` (blocks for one render, ~25-45 ms on a CPU; the controller runs meanwhile)."""
        color, depth, _ = self._render(snapshot, False)
        return RGBDFrame(color=color, depth_m=depth, intrinsics=self.intrinsics, stamp_ns=snapshot.stamp_ns,
                         mount=self.mount)

    def capture_d435(self, snapshot: PoseSnapshot) -> D435Pair:
        """Render ``snapshot`` as a D435 delivers it: colour and the depth imager's own picture (two renders)."""
        color, _, imager = self._render(snapshot, True)
        assert imager is not None
        return D435Pair(color, imager, snapshot.stamp_ns)

    def stats(self) -> FrameStats:
        times = self.render_ms or [0.0]
        return FrameStats(self.frames, times[-1], float(np.mean(times)))

    def stop(self) -> None:
        if self._process is None or self._conn is None or self._shm is None:
            return
        with contextlib.suppress(OSError):
            self._conn.send(None)
        self._process.join(timeout=5.0)
        if self._process.is_alive():
            self._process.kill()
            self._process.join(timeout=2.0)
        self._conn.close()
        self._shm.close()
        self._shm.unlink()
        self._process = self._conn = self._shm = None
