"""What watches a run without taking part in it: extra log content and wall-clock pacing.

None of these may change the run: they draw from no run random stream, step nothing and are read by no
leaf. ``LogExtras`` adds to the log (and the live view) what the leaves do not send: camera frames when a
leaf fails, at the end and optionally at a fixed simulated rate (rendered noise-free with
``render_color_async()``, which steps nothing and draws no noise; the renderer draws it while the run goes
on, and it is read back ``READBACK_TICKS`` ticks later and written with the stamp of the moment it shows), the
camera's frame from the calibration the run holds, and the judge's true object poses on
``/judge/true_objects`` (simulator truth: judge side only).
``RealtimePacer`` sleeps so wall time follows simulated time (pacing only; no decision reads it).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from bt_grasp.interfaces import Mount
from bt_grasp.recording import topics
from bt_grasp.recording.scene_entities import Solid, judge_update, object_model
from bt_grasp.recording.writer import BASE_FRAME, CAMERA_FRAME

if TYPE_CHECKING:
    from bt_grasp.behaviours.cell import Cell
    from bt_grasp.recording.writer import RunRecorder
    from bt_grasp.sim.camera import PendingPicture
    from bt_grasp.sim.world import World
    from bt_grasp.tree.loader import LoadedTree

log = logging.getLogger(__name__)

#: an extra frame is read back this many ticks after it was handed to the renderer (a count of ticks, not a
#: time: the log's bytes do not depend on the machine's speed); by then the renderer has drawn it beside the
#: run. Measured in one-off runs at 1 Hz: reading back after 40 ticks still waited 8-42 ms a frame for the
#: renderer, after 70 ticks ~4.5 ms (the copy); a frame reaches a live viewer this much simulated time late.
READBACK_TICKS = 60


@dataclass(frozen=True)
class _Pending:
    """A frame with the renderer: what it shows is the scene at ``stamp_ns``; read back at tick ``due``."""

    stamp_ns: int
    why: str
    started: float
    due: int
    picture: PendingPicture


class LogExtras:
    """Extra camera frames and judge truths for a run's log. ``start()``, every tick, ``finish()``."""

    def __init__(self, recorder: RunRecorder, world: World, cell: Cell, image_hz: float = 0.0) -> None:
        self.recorder = recorder
        self.world = world
        self.cell = cell
        self.period_ns = int(1e9 / image_hz) if image_hz > 0 else 0
        self._next_image_ns = 0
        self._failed = False
        self.captures = 0
        self._pending: list[_Pending] = []
        self._tick = 0
        self._camera_from: object = None
        recorder.event_listeners.append(self._on_event)

    def start(self) -> None:
        self.write_truth()

    def _on_event(self, kind: str, payload: Mapping[str, object]) -> None:
        if kind == "failure":
            self._failed = True

    def __call__(self, tick: int, tree: LoadedTree) -> None:
        self._tick = tick
        if not (self._pending or self._failed or self.period_ns) and self._camera_fixed():
            return  # the usual tick: no frame to write or take, the camera's frame unchanged
        self._write_ready()
        now = self.world.now_ns()
        self._update_camera_frame()
        periodic = self.period_ns > 0 and now >= self._next_image_ns
        if (self._failed or periodic) and self.recorder.active:
            self.capture("failure" if self._failed else "periodic")
            if self._failed:
                self.write_truth()
        self._failed = False
        if periodic:
            self._next_image_ns = now + self.period_ns

    def finish(self) -> None:
        self._update_camera_frame()
        if self.recorder.active:
            self.capture("end")
        self._write_ready(wait=True)
        self.write_truth()

    def _camera_fixed(self) -> bool:
        """Whether ``_update_camera_frame`` would change nothing (no calibration, or eye-to-hand and written)."""
        calibration = self.cell.calibration
        return calibration is None or (calibration is self._camera_from and calibration.mount != Mount.EYE_IN_HAND)

    def _update_camera_frame(self) -> None:
        """base_link -> camera from the calibration the run holds (eye-in-hand: follows the tool link)."""
        if self._camera_fixed():
            return  # no calibration, or eye-to-hand and written: fixed until the calibration changes
        calibration = self.cell.calibration
        assert calibration is not None
        self._camera_from = calibration
        T_base_tool = None
        if calibration.mount == Mount.EYE_IN_HAND:
            q = self.cell.robot.joint_positions()
            T_base_tool = self.cell.kinematics.fk_link(q, calibration.tool_link)
        T = np.asarray(calibration.T_base_camera_at(T_base_tool), dtype=np.float64)
        self.recorder.static_transforms[(BASE_FRAME, CAMERA_FRAME)] = T

    def capture(self, why: str) -> None:
        """Start a noise-free colour frame of the scene now: no noise drawn, nothing stepped. It is written,
        with its calibration and this moment's stamp, at the first tick after it is read back (or at the end)."""
        started = time.perf_counter()
        # periodic frames through the cheaper shader (its first frame costs ~50 ms more); the few failure and
        # end frames of a run without them through the pipeline's camera, warm since Perceive
        picture = self.world.camera.render_color_async(fast_shader=self.period_ns > 0)
        self._pending.append(_Pending(self.world.now_ns(), why, started, self._tick + READBACK_TICKS, picture))
        self.captures += 1

    def _write_ready(self, wait: bool = False) -> None:
        """Write the frames read back by now (all of them with ``wait``), oldest first."""
        while self._pending and (wait or self._pending[0].due <= self._tick or self._pending[0].picture.done()):
            frame = self._pending.pop(0)
            try:
                color = frame.picture.result()
            except Exception as exc:  # a lost picture must not end the run: say so in the log
                log.warning("a %s frame could not be read back: %s", frame.why, exc)
                self.recorder.write_log(frame.stamp_ns, "WARN", "log_camera", f"{frame.why} frame lost: {exc}")
                continue
            self.recorder.write_color_image(frame.stamp_ns, color, CAMERA_FRAME)
            self.recorder.write_camera_calibration(frame.stamp_ns, CAMERA_FRAME, self.world.camera.intrinsics)
            # the log says how many ticks later (the same on every machine: the file's bytes must not depend on its
            # speed); how long in wall time goes to Python's log only
            ticks_later = self._tick - (frame.due - READBACK_TICKS)
            message = f"{frame.why} frame (noise-free, for the log), read back {ticks_later} ticks later"
            self.recorder.write_log(frame.stamp_ns, "DEBUG", "log_camera", message)
            log.debug("%s frame read back after %.0f ms", frame.why, 1e3 * (time.perf_counter() - frame.started))

    def write_truth(self) -> None:
        """Where the simulator has every object now (the judge's view, for debugging perception offline)."""
        from bt_grasp.sim.judge_view import true_objects

        stamp = self.world.now_ns()
        solids = [Solid(f"true {o.name}", o.shape, o.size_m, o.T_world_object, (*o.rgb, 0.35))
                  if o.geometry is None else
                  Solid(f"true {o.name}", "model", o.size_m, o.T_world_object, (*o.rgb, 0.35), object_model(o.geometry))
                  for o in true_objects(self.world)]
        self.recorder.write_scene(topics.JUDGE_OBJECTS, stamp, judge_update(self.recorder.t(stamp), solids))


class RealtimePacer:
    """Sleeps after each tick until ``wall elapsed >= simulated elapsed / factor`` (factor 1 = real time)."""

    def __init__(self, world: World, factor: float = 1.0) -> None:
        if factor <= 0:
            raise ValueError(f"a real-time factor must be positive, got {factor}")
        self.world = world
        self.factor = float(factor)
        self._wall0: float | None = None
        self._sim0 = 0

    def __call__(self, tick: int, tree: LoadedTree) -> None:
        if self._wall0 is None:
            self._wall0, self._sim0 = time.monotonic(), self.world.now_ns()
            return
        due = self._wall0 + (self.world.now_ns() - self._sim0) * 1e-9 / self.factor
        delay = due - time.monotonic()
        if delay > 0:
            time.sleep(delay)
