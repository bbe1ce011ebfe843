"""FollowTarget: keep the tool centred over a (moving) object at a standoff height, closed loop on the camera.

One control period per tick (100 Hz of simulated time); a camera measurement every 1/rate s of simulated
time (15 Hz by default, a D435's colour stream at a modest rate). The first measurement is a full
perception (plane, clusters, geometry: the object's size and yaw) unless a previous FollowTarget handed its
``track`` over; later ones are the light colour-blob tracker (``bt_grasp.perception.tracking``). The law is
position-based visual servoing: a PID on the tcp's position error with the target's velocity fed forward
(see ``servo.py`` for why), turned into joint position + velocity targets through the kinematic model.

SUCCESS when the error has stayed under ``tolerance`` for ``converged_time`` s (a negative time: follow
until halted, e.g. beside ``Grasp`` in a ``Parallel``); FAILURE ``TARGET_LOST`` when no measurement came
for ``lost_after`` s; RUNNING otherwise. Halting (or failing) brings the arm to rest smoothly over ~0.1 s.
Every measurement, error and command goes to the run's log (``/bt/events`` kind ``servo``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.base import RobotLeaf
from bt_grasp.behaviours.perceive import camera_pose, perceive_once
from bt_grasp.behaviours.reasons import FailureReason
from bt_grasp.behaviours.servo import Gains, PidLaw, TargetTrack, grasp_yaw, rotate_towards
from bt_grasp.geometry import make_T, rot_z
from bt_grasp.tree.node_api import Status, action, inout_port, input_port

if TYPE_CHECKING:
    from bt_grasp.perception.tracking import BlobMeasurement

#: the tcp stays this far above the object's support (finger tips 20 mm below the tcp, 5 mm clearance)
MIN_TCP_ABOVE_SUPPORT_M = 0.025
#: a blob further than this from where the track expects the target is another object (ignored)
_GATE_M = 0.06
#: a blob with less than this share of the recent blobs' median area is partly hidden: not a measurement
_MIN_AREA_RATIO = 0.6
#: the commanded tcp position runs at most this far ahead of the measured one, m
_REF_LEAD_M = 0.02
#: the tool turns to the grasp yaw at most this fast, rad/s
_MAX_TURN_RAD_S = 1.5
#: halting: the arm is brought to rest over about this long, s
_STOP_TIME_S = 0.1
#: a full frame (colour, depth, cloud) is logged every this many measurements (the numbers every time)
_FRAME_LOG_EVERY = 5


@action(
    ports=[
        input_port("color", str, "{color}", "the target's colour name"),
        input_port("standoff", float, 0.15, "tcp height above the target's centre, m"),
        input_port("kp", float, 4.0, "proportional gain, 1/s"),
        input_port("ki", float, 1.0, "integral gain, 1/s^2"),
        input_port("kd", float, 0.0, "derivative gain"),
        input_port("tolerance", float, 0.006, "converged when the tcp is this close, m"),
        input_port("converged_time", float, 0.5,
                   "SUCCESS after this long converged, s (negative: follow until halted)"),
        input_port("rate", float, 15.0, "camera measurements per second (simulated time)"),
        input_port("lost_after", float, 0.6, "TARGET_LOST after this long unseen, s"),
        inout_port("track", object, "the target's track: continued if set (a previous FollowTarget), written every "
                   "tick", default="{track}"),
    ],
    reasons=(FailureReason.BAD_INPUT, FailureReason.TARGET_LOST, FailureReason.IK_UNREACHABLE),
    needs_robot=True,
)
class FollowTarget(RobotLeaf):
    """Follow an object of a colour with the tool, at a standoff, on camera measurements (both mounts)."""

    def initialise(self) -> None:
        self._early: Status | None = None
        self._track: TargetTrack | None = None
        gain = self.ports.require
        self._pid = PidLaw(Gains(gain("kp", float), gain("ki", float), gain("kd", float)))
        self._last_capture_s = float("-inf")
        self._converged_since: float | None = None
        self._measurements = 0
        color = self.ports.get("color", str) or ""
        config = self.cell.perception_config
        if color not in config.color.ranges:
            self._early = self.fail(FailureReason.BAD_INPUT, f"unknown colour '{color}'; known: "
                                      f"{', '.join(config.color.ranges)}")
            return
        if self.ports.require("rate", float) <= 0 or self.ports.require("tolerance", float) <= 0:
            self._early = self.fail(FailureReason.BAD_INPUT, "rate and tolerance must be positive")
            return
        previous = self.ports.get("track")
        if isinstance(previous, TargetTrack) and previous.color == color and previous.samples:
            self._track = previous
        else:
            self._early = self._start_track(color)
        q = self.cell.robot.joint_positions()
        T = self.cell.kinematics.fk(q)
        self._R_ref = T[:3, :3].copy()
        self._x_ref = T[:3, 3].copy()  # the commanded tcp position, integrated from the commanded velocity
        self._q_cmd = q.copy()
        if self._track is not None:
            yaw_now = float(np.arctan2(T[1, 0], T[0, 0]))
            self._R_goal = rot_z(grasp_yaw(self._track, yaw_now)) @ np.diag([1.0, -1.0, -1.0])

    def _start_track(self, color: str) -> Status | None:
        """A full perception to find the target and learn its size and yaw."""
        result = perceive_once(self, color)
        if isinstance(result, Status):
            return result
        det = result.best
        assert det is not None
        self._track = TargetTrack(color=color, height_m=float(det.size_m[2]), yaw_rad=float(det.yaw_rad),
                                  length_m=float(det.size_m[0]), width_m=float(det.size_m[1]),
                                  round=det.shape == "round")
        self._track.add(self.now_s(), np.asarray(det.centroid_base_m, dtype=float))
        self._last_capture_s = self.now_s()
        return None

    # --- measuring -----------------------------------------------------------------------------------
    def _measure(self, t_s: float) -> BlobMeasurement | None:
        # deferred: Open3D and OpenCV come with it; a tree loads and validates without them
        from bt_grasp.perception.tracking import Footprint, measure_blob

        track = self._track
        assert track is not None
        T_base_camera = camera_pose(self.cell)
        frame = self.cell.camera.capture()
        if frame is None or T_base_camera is None:
            return None
        self._measurements += 1
        if self._measurements % _FRAME_LOG_EVERY == 1:
            self.cell.media.frame(frame, T_base_camera)
        expected, _ = track.predict(t_s)
        top = expected + np.array([0.0, 0.0, track.height_m / 2])
        footprint = Footprint(track.length_m, track.width_m, track.yaw_rad)
        m = measure_blob(frame, T_base_camera, track.color, self.cell.perception_config,
                         top_z_hint_m=track.top_z_m, expected_base_m=top, footprint=footprint,
                         support_z_m=track.top_z_m - track.height_m)
        if m is None:
            return None
        # the object rides on a flat support: its height stays what the full perception measured; a blob
        # much smaller than the recent ones is partly hidden (by the gripper) and would pull the centre
        centre = np.array([m.xy_base_m[0], m.xy_base_m[1], expected[2]])
        if float(np.linalg.norm(centre[:2] - expected[:2])) > _GATE_M:
            return None
        if track.areas and m.area_px < _MIN_AREA_RATIO * float(np.median(track.areas)):
            return None
        track.areas.append(m.area_px)
        track.add(t_s, centre)
        return m

    # --- the loop ------------------------------------------------------------------------------------
    def update(self) -> Status:
        if self._early is not None:
            return self._early
        track = self._track
        assert track is not None
        t = self.now_s()
        measurement = None
        if t - self._last_capture_s >= 1.0 / self.ports.require("rate", float) - 1e-9:
            self._last_capture_s = t
            measurement = self._measure(t)
        if t - track.last_time_s > self.ports.require("lost_after", float):
            self._stop()
            return self.fail(FailureReason.TARGET_LOST,
                               f"the {track.color} target has been out of view for {t - track.last_time_s:.2f} s")
        status = self._control(t, track, measurement)
        self.ports.set("track", track)
        return status

    def _control(self, t: float, track: TargetTrack, measurement: BlobMeasurement | None) -> Status:
        robot, kin = self.cell.robot, self.cell.kinematics
        dt = 1.0 / self.cell.scene.physics.control_rate_hz
        position, velocity = track.predict(t)
        support_z = position[2] - track.height_m / 2
        goal_z = max(position[2] + self.ports.require("standoff", float), support_z + MIN_TCP_ABOVE_SUPPORT_M)
        desired = np.array([position[0], position[1], goal_z])
        q = robot.joint_positions()
        T_now = kin.fk(q)
        error = desired - T_now[:3, 3]
        u = self._pid.command(error, velocity, dt)
        self._R_ref = rotate_towards(self._R_ref, self._R_goal, _MAX_TURN_RAD_S * dt)
        # integrate the command into a reference the joint drives hold: a lagging arm sees its position
        # target move ahead until it catches up (no steady offset), never more than _REF_LEAD_M ahead
        self._x_ref = self._x_ref + u * dt
        lead = self._x_ref - T_now[:3, 3]
        if float(np.linalg.norm(lead)) > _REF_LEAD_M:
            self._x_ref = T_now[:3, 3] + lead * (_REF_LEAD_M / float(np.linalg.norm(lead)))
        T_cmd = make_T(self._R_ref, self._x_ref)
        ik = kin.ik(T_cmd, self._q_cmd, seeds=1)
        if not ik.ok:
            self._stop()
            return self.fail(FailureReason.IK_UNREACHABLE,
                               f"the tool cannot follow the target to ({desired[0]:.3f}, {desired[1]:.3f}, "
                               f"{desired[2]:.3f}) m")
        q_cmd = np.asarray(ik.q, dtype=float)
        robot.set_joint_targets(q_cmd, (q_cmd - self._q_cmd) / dt)
        self._q_cmd = q_cmd
        self._record(t, position, velocity, T_now[:3, 3], error, u, measurement)
        err = float(np.linalg.norm(error))
        self.feedback_message = f"error {err * 1e3:.1f} mm, target speed {np.linalg.norm(velocity) * 100:.1f} cm/s"
        if err < self.ports.require("tolerance", float) and self._turned():
            self._converged_since = t if self._converged_since is None else self._converged_since
        else:
            self._converged_since = None
        hold = self.ports.require("converged_time", float)
        if hold >= 0 and self._converged_since is not None and t - self._converged_since >= hold - 1e-9:
            return Status.SUCCESS
        return Status.RUNNING

    def _turned(self) -> bool:
        return bool(np.allclose(self._R_ref, self._R_goal, atol=1e-3))

    def _record(self, t: float, position: NDArray[np.float64], velocity: NDArray[np.float64],
                tcp: NDArray[np.float64], error: NDArray[np.float64], u: NDArray[np.float64],
                measurement: BlobMeasurement | None) -> None:
        values: dict[str, float | bool | str] = {
            "t_s": t,
            "target_x_m": float(position[0]), "target_y_m": float(position[1]), "target_z_m": float(position[2]),
            "target_vx_m_s": float(velocity[0]), "target_vy_m_s": float(velocity[1]),
            "tcp_x_m": float(tcp[0]), "tcp_y_m": float(tcp[1]), "tcp_z_m": float(tcp[2]),
            "error_x_m": float(error[0]), "error_y_m": float(error[1]), "error_z_m": float(error[2]),
            "cmd_vx_m_s": float(u[0]), "cmd_vy_m_s": float(u[1]), "cmd_vz_m_s": float(u[2]),
        }
        if measurement is not None:
            values.update({"meas_x_m": measurement.xy_base_m[0], "meas_y_m": measurement.xy_base_m[1],
                           "meas_top_z_m": measurement.top_z_m, "meas_area_px": float(measurement.area_px),
                           "meas_used_depth": measurement.used_depth})
        self.cell.media.servo(self.name, values)

    def _stop(self) -> None:
        """Bring the arm to rest smoothly: hold where it would be after decelerating over _STOP_TIME_S."""
        robot = self.cell.robot
        q, qd = robot.joint_positions(), robot.joint_velocities()
        robot.set_joint_targets(q + qd * (_STOP_TIME_S / 2), np.zeros_like(q))

    def terminate(self, new_status: Status) -> None:
        if new_status in (Status.IDLE, Status.FAILURE) and getattr(self, "_track", None) is not None:
            self._stop()
