"""A twin: a scene's simulated cell served as a UR controller, a Robotiq gripper and a camera, in real time.

:class:`Twin` composes the pieces: the SAPIEN world (with the chosen gripper), the controller and its cycle
thread, the ports (RTDE 30004, dashboard 29999, script 30003, gripper 63352, the twin's control port), the judge
and the camera's render process. ``start``/``stop`` bracket it; the methods below are the Python API of the
control port (faults, verdicts, frames).
"""

from __future__ import annotations

import logging
import socket
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import TypeAdapter, ValidationError

from bt_grasp.cell.grippers import GRIPPERS, BoardLayout, GripperName, T_tool_board, robot_urdf_path_with
from bt_grasp.interfaces import RGBDFrame
from bt_grasp.scene.format import Scene, load_scene
from bt_grasp.scene.goals import Goal
from bt_grasp.scene.run_goal import goal_for_run
from bt_grasp.sim.judge import Judge, Verdict, cannot_judge
from bt_grasp.sim.twin.camera_port import CameraPort, D435Description
from bt_grasp.sim.twin.camera_worker import D435Pair, PoseSnapshot, TwinCamera
from bt_grasp.sim.twin.cell_writer import home_for
from bt_grasp.sim.twin.config import CAMERA_PORT, DASHBOARD_PORT, GRIPPER_PORT, RTDE_PORT, SCRIPT_PORT, TwinConfig
from bt_grasp.sim.twin.control_port import ControlSession, RequestError
from bt_grasp.sim.twin.controller import Controller
from bt_grasp.sim.twin.dashboard import DashboardSession
from bt_grasp.sim.twin.faults import TwinFault
from bt_grasp.sim.twin.gripper_port import GripperSession, GripperSilence
from bt_grasp.sim.twin.kinematics import UrKinematics
from bt_grasp.sim.twin.netio import IoLoop, Protocol
from bt_grasp.sim.twin.plant import SapienPlant
from bt_grasp.sim.twin.realtime import RealtimeLoop
from bt_grasp.sim.twin.robotiq import Robotiq2F85
from bt_grasp.sim.twin.rtde_server import RtdeHub
from bt_grasp.sim.twin.script_port import ScriptSession
from bt_grasp.sim.twin.state import InputBank
from bt_grasp.sim.world import World

log = logging.getLogger(__name__)

DEFAULT_CAMERA_HZ = 15.0
DEFAULT_DROP_S = 1.0


def check_ports_free(host: str, control_port: int, camera_port: int = CAMERA_PORT) -> None:
    """Raise OSError naming the first of the twin's ports that cannot be bound on ``host`` (before a world is
    built: a taken address fails in a moment, not after the simulator started)."""
    for name, port in (("RTDE", RTDE_PORT), ("dashboard", DASHBOARD_PORT), ("script", SCRIPT_PORT),
                       ("gripper", GRIPPER_PORT), ("control", control_port), ("camera", camera_port)):
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            try:
                probe.bind((host, port))
            except OSError as exc:
                raise OSError(exc.errno, f"{host}:{port} ({name}): {exc.strerror}") from exc


class Twin:
    """One twin. Not started until :meth:`start`; :meth:`stop` ends every thread and the render process."""

    def __init__(self, scene_path: str | Path, config: TwinConfig | None = None, seed: int = 0) -> None:
        self.config = config or TwinConfig()
        self.scene_path = Path(scene_path)
        self.scene: Scene = load_scene(self.scene_path)
        self.seed = int(seed)
        self.gripper_model = GRIPPERS[self.config.gripper]
        urdf = robot_urdf_path_with(self.config.gripper)
        self.world = World(self.scene, self.seed, source=self.scene_path,
                           robot_urdf=None if self.config.gripper == GripperName.BT_GRASP else urdf)
        #: where the arm starts: the scene's home, with a longer gripper's TCP where bt_grasp's is at home (the
        #: cell file's home; bt_grasp.sim.twin.cell_writer.home_for)
        self.home_q = home_for(self.scene, self.gripper_model)
        self.world.robot.reset(self.home_q)
        self.plant = SapienPlant(self.world)
        self.inputs = InputBank()
        self.gripper = Robotiq2F85(self.gripper_model, self.plant)
        T_flange_tcp = np.eye(4)
        T_flange_tcp[2, 3] = self.gripper_model.tcp_z_m
        self.controller = Controller(self.config, self.plant, UrKinematics(), self.inputs, T_flange_tcp,
                                     self.gripper)
        self._judge = Judge(self.world)
        if self.scene.goal is not None and Judge.places(self.scene.goal):
            self.controller.after_cycle.append(lambda _state: self._judge.observe())
        self.hub = RtdeHub(self.config.model.version, self.config.model.rate_hz, self.inputs)
        self.silence = GripperSilence()
        timeout = self.config.message_timeout_s
        model = self.config.model
        self.io = IoLoop(self.config.host, [
            Protocol("RTDE", RTDE_PORT, self.hub.make_session, 16, timeout),
            Protocol("dashboard", DASHBOARD_PORT, lambda link: DashboardSession(link, self.controller, model), 8,
                     timeout),
            Protocol("script", SCRIPT_PORT, lambda link: ScriptSession(link, self.controller), 8, timeout),
            Protocol("gripper", GRIPPER_PORT, lambda link: GripperSession(link, self.gripper, self.silence), 4,
                     timeout),
            Protocol("control", self.config.control_port, lambda link: ControlSession(link, self), 4, timeout),
        ], realtime_priority=(self.config.realtime_priority or 0) - 1 or None)
        self.loop = RealtimeLoop(self.config.period_s, self._cycle, realtime_priority=self.config.realtime_priority)
        #: the calibration board on the gripper (``--board``): its layout and true pose on tool0 (the palm's frame)
        self.board: tuple[BoardLayout, np.ndarray] | None = None
        if self.config.board:
            layout = BoardLayout()
            self.board = (layout, T_tool_board(self.gripper_model, layout))
        board_arg = None if self.board is None else (self.board[0].as_dict(), self.board[1].tolist())
        self._camera = TwinCamera(str(self.scene_path), self.seed, self.config.gripper.value,
                                  self.world.camera.intrinsics, self.world.camera.mount, board_arg)
        self.camera_port = CameraPort(self.config.host, self.config.camera_port, self._d435_description(),
                                      self.capture_d435, self.config.message_timeout_s)
        self._stream_stop = threading.Event()
        self._stream: threading.Thread | None = None
        self._started = False

    # --- life ---------------------------------------------------------------------------------------------
    def start(self) -> None:
        """Bind every port (OSError naming the port if one is taken), then serve."""
        self.io.bind()
        try:
            self.camera_port.bind()
        except OSError:
            self.io.close_listeners()
            raise
        self._camera.start()
        self.io.start()
        self.camera_port.start()
        self.loop.start()
        self._started = True
        log.info("twin serving %s on %s (RTDE %d, dashboard %d, script %d, gripper %d, control %d, camera %d)",
                 self.scene_path.name, self.config.host, RTDE_PORT, DASHBOARD_PORT, SCRIPT_PORT, GRIPPER_PORT,
                 self.config.control_port, self.config.camera_port)

    def stop(self) -> None:
        self._stream_stop.set()
        if self._stream is not None:
            self._stream.join(timeout=2.0)
        self.loop.stop()
        self.io.stop()
        self.camera_port.stop()
        if self._started:
            self._camera.stop()
        self._started = False

    def _cycle(self) -> None:
        state = self.controller.tick()
        self.hub.publish(self.controller.cycle, state)

    # --- the control port's API ---------------------------------------------------------------------------
    def status(self) -> dict[str, Any]:
        state = self.controller.snapshot()
        frames = self._camera.stats()
        return {
            "robot_mode": state.robot_mode.name, "safety_mode": state.safety_mode.name,
            "runtime_state": state.runtime_state.name, "timestamp_s": round(state.timestamp_s, 6),
            "actual_q": [round(float(v), 6) for v in state.actual_q],
            "actual_qd": [round(float(v), 6) for v in state.actual_qd],
            "gripper_opening_m": round(self.plant.opening_m(), 5),
            **{k: round(v, 3) for k, v in self.loop.period_stats().items()}, "realtime": self.loop.realtime,
            "camera_frames": frames.frames, "camera_render_ms": round(frames.mean_render_ms, 2),
        }

    def inject(self, fault: TwinFault, seconds: float | None = None) -> str:
        """Produce ``fault`` now (``seconds``: how long a dropped network stays down); returns what was done."""
        return _FAULTS[fault](self, seconds)

    def _protective_stop(self, _: float | None) -> str:
        self.controller.protective_stop("injected (the twin's fault protective-stop)")
        return "protective stop"

    def _pendant_stop(self, _: float | None) -> str:
        self.controller.stop_program("stopped from the pendant (the twin's fault pendant-stop)")
        return "program stopped"

    def _drop_connections(self, seconds: float | None) -> str:
        span = DEFAULT_DROP_S if seconds is None else seconds
        dropped = self.io.drop_all(span, spare=("control",))  # the twin's own port is not the robot's network
        return f"{dropped} connections dropped, new ones refused for {span:g} s"

    def _gripper(self, silent: bool) -> str:
        self.silence.set(silent)
        sentence = "the gripper stops answering" if silent else "the gripper answers again"
        log.warning("fault: %s", sentence)
        return sentence

    def verdict(self, goal: Goal | None = None) -> Verdict:
        """The physics judge's verdict on ``goal`` (None: the scene's goal, or a pick of its default colour)."""
        goal = goal or goal_for_run(self.scene, {})
        with self.controller.lock:
            return self._judge.check(goal)

    def goal(self) -> dict[str, Any]:
        """The goal a run is judged on unless it names one (the task's declaration, as a scene file gives a
        simulated run: not ground truth)."""
        return {"goal": goal_for_run(self.scene, {}).model_dump(mode="json")}

    def judge(self, goal_json: str | None) -> dict[str, Any]:
        goal: Goal | None = None
        if goal_json is not None:
            try:
                goal = TypeAdapter(Goal).validate_json(goal_json)
            except ValidationError as exc:
                first = exc.errors()[0]
                where = ".".join(str(p) for p in first["loc"])
                raise RequestError(f"the goal is not a scene goal: {first['msg']} at {where or 'the top'}") from None
            problem = cannot_judge(goal)
            if problem is not None:
                raise RequestError(problem)
        verdict = self.verdict(goal)
        return {
            "success": verdict.success, "goal": verdict.goal.model_dump(mode="json"),
            "conditions": [{"criterion": c.criterion.value, "met": c.met, "detail": c.detail}
                           for c in verdict.conditions],
            "object": verdict.object_name, "object_lift_m": round(verdict.object_lift_m, 5),
            "in_gripper": verdict.in_gripper,
        }

    def snapshot(self) -> PoseSnapshot:
        """What the camera should show now (taken between two controller cycles)."""
        with self.controller.lock:
            qpos = tuple(float(v) for v in self.world.robot.articulation.get_qpos())
            poses = []
            for entity in self.world.objects.values():
                pose = entity.get_pose()
                poses.append((*map(float, pose.p), *map(float, pose.q)))
            stamp = int(self.controller.state.timestamp_s * 1e9)
        return PoseSnapshot(qpos, tuple(poses), stamp)

    def capture(self) -> RGBDFrame:
        """One camera frame of the cell as it is now (rendered in the camera process)."""
        return self._camera.capture(self.snapshot())

    def capture_d435(self) -> D435Pair:
        """One frame of the cell as it is now as a D435 delivers it: colour and the depth imager's own picture."""
        return self._camera.capture_d435(self.snapshot())

    def _d435_description(self) -> D435Description:
        from bt_grasp.sim.depth_imager import DepthImagerModel  # deferred: the render-side model, once

        color = self.world.camera.intrinsics
        model = DepthImagerModel.d435(color.width_px, color.height_px)
        return D435Description(color, model.intrinsics, model.T_color_depth, self.world.camera.mount.value)

    def truth(self, what: str) -> dict[str, Any]:
        """Ground truth for tests and benchmarks (the judge's side, never the pipeline's): ``camera``, the true
        camera pose in the base frame (eye-to-hand) or on the tool (eye-in-hand)."""
        if what != "camera":
            raise RequestError(f"truth takes camera, got {what!r}")
        from bt_grasp.sim.judge import true_camera_pose  # deferred: the oracle only when the truth is asked for

        mount = self.world.camera.mount.value
        with self.controller.lock:
            T = true_camera_pose(self.world, mount, "tool0")
        return {"mount": mount, "T_true": [[float(v) for v in row] for row in T]}

    def camera(self, action: str, rate_hz: float | None) -> dict[str, Any]:
        if action == "capture":
            frame = self.capture()
            stats = self._camera.stats()
            return {"frame": stats.frames, "render_ms": round(stats.last_render_ms, 2),
                    "stamp_ns": frame.stamp_ns}
        if action == "off":
            self._stream_stop.set()
            if self._stream is not None:
                self._stream.join(timeout=2.0)
            self._stream = None
            return {"camera": "off", "frames": self._camera.stats().frames}
        if self._stream is not None:
            self._stream_stop.set()
            self._stream.join(timeout=2.0)
        rate = rate_hz or DEFAULT_CAMERA_HZ
        self._stream_stop = threading.Event()
        self._stream = threading.Thread(target=self._stream_frames, args=(rate, self._stream_stop),
                                        name="twin-camera-stream", daemon=True)
        self._stream.start()
        return {"camera": "on", "rate_hz": rate}

    def _stream_frames(self, rate_hz: float, stop: threading.Event) -> None:
        """Capture at ``rate_hz`` (or as fast as the renderer goes, if slower), until ``stop``."""
        period = 1.0 / rate_hz
        deadline = time.monotonic()
        while not stop.is_set():
            try:
                self.capture()
            except (TimeoutError, OSError, EOFError) as exc:
                log.warning("the camera stream stopped: %s", exc)
                return
            deadline = max(deadline + period, time.monotonic())
            stop.wait(deadline - time.monotonic())


#: what each fault of :class:`TwinFault` does to a twin (bt_grasp.sim.twin.faults says what a client sees)
_FAULTS: dict[TwinFault, Callable[[Twin, float | None], str]] = {
    TwinFault.PROTECTIVE_STOP: Twin._protective_stop,
    TwinFault.PENDANT_STOP: Twin._pendant_stop,
    TwinFault.DROP_CONNECTIONS: Twin._drop_connections,
    TwinFault.GRIPPER_SILENT: lambda twin, _: twin._gripper(True),
    TwinFault.GRIPPER_ANSWERS: lambda twin, _: twin._gripper(False),
}
