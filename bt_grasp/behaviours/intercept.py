"""InterceptPick: meet an object on a running belt, ride with it, grasp it and lift it off, one control period a tick.

The object comes from ``TrackOnBelt`` with its track (``bt_grasp.perception.belt_track``: where it will be, how
sure that is) and the watch that keeps the track fed (frames at ``rate``, handed over the cell's perception latency
after they were taken; the belt's encoder every tick). The leaf chooses a grasp of the object as it lies (the
pipeline's ranking of its last detection, kept to grasps from within 30 degrees of straight down: the tool descends
with the belt), then the intercept (``bt_grasp.motion.intercept``): the earliest time the arm, from where it is,
can be ``hover`` above that grasp moving with the belt, with the whole ride inside the arm's reach. Then, tick by
tick:

1. **approach**: the jerk-limited joint trajectory to the intercept; every fresh detection re-plans it for the same
   arrival time from the state the arm is commanded to be in (until 0.15 s before the arrival), or for another
   when that time is no longer feasible; when none is, the approach goes on as planned as long as the fresh
   estimate puts the object within 1 cm of where it was planned for (else the intercept is missed);
2. **descend**: the tool follows the object's predicted grasp pose and descends to it in ``descend`` s (a quintic:
   at contact the tool moves exactly with the belt); what the approach's end missed of the latest estimate is
   taken up over the first 0.2 s;
3. **close**: the fingers close with ``force`` N while the tool keeps riding with the object, until their width
   settles (at most 0.4 s; 0.25 s on a belt faster than 35 cm/s, whose descent is 0.25 s too);
4. **lift**: the tool rises by ``lift`` m while it slows from the belt's speed to rest (once the object is clear of
   the belt).

Each tick the commanded joint positions are the inverse kinematics of the tool pose for the middle of the coming
control period, with the joint velocity that moves it on (feed-forward). FAILURE: ``INTERCEPT_MISSED`` (no
intercept is left: the object will leave the reach before the ride is over, or the arm can no longer follow it),
``GRASP_EMPTY`` (the fingers closed on nothing), ``NOTHING_TO_GRASP`` (no grasp of the object from above),
``BAD_INPUT`` (no tracked object). Every tick's prediction, its sigma, the phase and the tool's position go to the
log (``/bt/events``, kind ``servo``).
"""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.base import RobotLeaf
from bt_grasp.behaviours.belt_watch import BeltTarget
from bt_grasp.behaviours.gripper import empty_below_m
from bt_grasp.behaviours.reasons import FailureReason
from bt_grasp.seeds import Stream
from bt_grasp.tree.node_api import Status, action, input_port, output_port

if TYPE_CHECKING:
    from bt_grasp.motion.intercept import Approach, BeltGrasp, InterceptPlanner
    from bt_grasp.perception.results import Detection, GraspCandidate

INTERCEPT_MISSED = FailureReason.INTERCEPT_MISSED

#: the tool descends along an approach at most this far from straight down, degrees
MAX_TILT_DEG = 30.0
#: grasps tried for an intercept (the one whose intercept comes first is taken) ...
MAX_GRASPS = 3
#: ... among those scored at least this share of the best
GOOD_SHARE = 0.85
#: no re-planning of the approach closer to the arrival than this, s
COMMIT_S = 0.15
#: an approach that cannot be re-planned goes on while the object is predicted this close to where it was planned for
DRIFT_M = 0.01
#: the difference between where the approach arrived and the latest estimate is taken up over this long, s
BLEND_S = 0.2
#: the fingers count as settled after this many ticks changing less than SETTLED_M each ...
SETTLED_TICKS = 3
SETTLED_M = 0.0003
#: ... but no sooner than this after the command, s
MIN_CLOSE_S = 0.08
#: a commanded joint moves at most this far in a tick while riding with the object (more: another arm branch), rad
MAX_STEP_RAD = 0.3
#: halting: the arm is brought to rest over about this long, s
STOP_TIME_S = 0.1

_APPROACH, _DESCEND, _CLOSE, _LIFT, _DONE = "approach", "descend", "close", "lift", "done"


@action(
    ports=[
        input_port("target", object, "{belt_target}", "the tracked object (from TrackOnBelt)"),
        input_port("force", float, 40.0, "finger force, N"),
        input_port("lift", float, 0.15, "how far the object rises off the belt, m"),
        input_port("rate", float, 15.0, "frames per second while the object is watched (simulated time)"),
        input_port("hover", float, 0.08, "the tool arrives this far above its grasp pose, m"),
        input_port("descend", float, 0.0, "the descent from there to the grasp, riding with the belt, s (0: 0.4, "
                   "0.25 on a belt faster than 35 cm/s)"),
        output_port("grasp", object, "the grasp as it closed (its tool pose and width)", default="{grasp}"),
        output_port("held", object, "the object's detection where it was grasped", default="{target}"),
    ],
    reasons=(INTERCEPT_MISSED, FailureReason.GRASP_EMPTY, FailureReason.NOTHING_TO_GRASP, FailureReason.BAD_INPUT),
    needs_robot=True,
)
class InterceptPick(RobotLeaf):
    """Intercept a tracked object on a running belt, grasp it riding with the belt, lift it off."""

    def initialise(self) -> None:
        # deferred: ruckig and pinocchio come with it; a tree loads and validates without them
        from bt_grasp.motion.intercept import ArmState, InterceptSettings

        self._early: Status | None = None
        self._phase = _APPROACH
        self._t_arrive = self._t_close = self._grasped_at = 0.0
        self._t_lift: float | None = None
        self._blend = np.zeros(3)
        self._last_width, self._still = 0.0, 0
        self._approach: Approach | None = None
        self._planner: InterceptPlanner | None = None
        self._grasp: BeltGrasp | None = None
        target = self.ports.get("target")
        if not isinstance(target, BeltTarget):
            self._early = self.fail(FailureReason.BAD_INPUT, "'target' is not a tracked object: run TrackOnBelt first")
            return
        self.watch, self.track = target.watch, target.track
        self.settings = InterceptSettings.for_belt(self.track.axis.nominal_speed_m_s,
                                                   hover_m=self.ports.require("hover", float),
                                                   descend_s=self.ports.require("descend", float))
        self.dt = 1.0 / self.cell.scene.physics.control_rate_hz
        q = self.cell.robot.joint_positions()
        self._q_cmd = q.copy()
        self._state = ArmState.at_rest(q)
        self._early = self._plan_first()

    # --- choosing the grasp and the intercept -------------------------------------------------------------------
    def _grasps(self, det: Detection) -> list[BeltGrasp]:
        """The grasps worth an intercept: from within MAX_TILT_DEG of straight down, scored at least GOOD_SHARE of the
        best, the tool's yaw nearest the tool's now first (a parallel gripper's two flips are one grasp; turning the
        wrist takes time), at most MAX_GRASPS."""
        # deferred: Open3D comes with it; a tree loads and validates without it
        from bt_grasp.motion.intercept import BeltGrasp
        from bt_grasp.perception.antipodal import rank_grasps  # deferred: as above

        ranked = rank_grasps(det, (), self.cell.grasp_settings, seed=self.cell.seeds.integer(Stream.GRASPS))
        cos_tilt = float(np.cos(np.deg2rad(MAX_TILT_DEG)))
        down = [c for c in ranked.candidates if float(-np.asarray(c.T_base_tcp_grasp)[2, 2]) >= cos_tilt]
        if not down:
            return []
        best = max(c.score for c in down)
        good = [c for c in down if c.score >= GOOD_SHARE * best] if best > 0 else down
        T_now = self.cell.kinematics.fk(self._q_cmd)
        yaw_now = float(np.arctan2(T_now[1, 0], T_now[0, 0]))

        def turn(c: GraspCandidate) -> float:
            T = np.asarray(c.T_base_tcp_grasp)
            return abs(float(np.angle(np.exp(1j * (np.arctan2(T[1, 0], T[0, 0]) - yaw_now)))))

        good.sort(key=turn)
        centroid = np.asarray(det.centroid_base_m, dtype=float)
        return [BeltGrasp.from_pose(np.asarray(c.T_base_tcp_grasp), centroid, c.width_m) for c in good[:MAX_GRASPS]]

    def _plan_first(self) -> Status | None:
        """The grasp whose intercept comes first, and that intercept."""
        # deferred: ruckig and pinocchio come with it; a tree loads and validates without them
        from bt_grasp.motion.intercept import InterceptPlanner, reach_window

        track, now = self.track, self.now_s()
        grasps = self._grasps(track.detection)
        if not grasps:
            return self.fail(FailureReason.NOTHING_TO_GRASP, f"no grasp of the {track.detection.label} object from "
                             f"within {MAX_TILT_DEG:.0f} degrees of straight down")
        axis = track.axis
        z = float(track.predict(now).position_m[2])
        tool_along = axis.along(self.cell.kinematics.fk(self._q_cmd)[:3, 3])
        for grasp in grasps:
            window = reach_window(self.cell.kinematics, lambda s: axis.point(s, track.across_m, z), grasp,
                                  self.settings.hover_m, self._q_cmd, axis.length_m, tool_along,
                                  self.settings.max_reach_m)
            if window.empty:
                continue
            planner = InterceptPlanner(self.cell.kinematics, grasp, window, self.settings, axis.along)
            approach = planner.plan(now, self._state, self._centroid_at, track.predict(now).velocity_m_s)
            if approach is not None and (self._approach is None or approach.arrive_s < self._approach.arrive_s - 1e-9):
                self._planner, self._grasp, self._approach = planner, grasp, approach
        if self._approach is not None:
            self.feedback_message = (f"intercept in {self._approach.arrive_s - now:.2f} s at "
                                     f"{self._approach.along_m:.3f} m along the belt")
            return None
        p = track.predict(now)
        return self.fail(INTERCEPT_MISSED, f"no intercept of the {track.detection.label} object at {p.along_m:.2f} m "
                         f"along the belt ({np.linalg.norm(p.velocity_m_s) * 100:.0f} cm/s): it leaves the reach "
                         "before a grasp could be over")

    def _centroid_at(self, t_s: float) -> NDArray[np.float64]:
        return self.track.predict(t_s).position_m

    # --- the loop -----------------------------------------------------------------------------------------------
    def update(self) -> Status:
        if self._early is not None:
            return self._early
        looking = self._phase in (_APPROACH, _DESCEND)
        updated = self.watch.step(self, self.ports.require("rate", float), look=looking)
        now = self.now_s()
        fresh = self.track in updated
        status = self._approach_step(now, fresh) if self._phase == _APPROACH else self._match_step(now)
        self._record(now)
        return status

    def _approach_step(self, now: float, fresh: bool) -> Status:
        approach, planner = self._approach, self._planner
        assert approach is not None and planner is not None
        if fresh and approach.arrive_s - now > COMMIT_S:
            velocity = self.track.predict(now).velocity_m_s
            again = planner.plan(now, approach.sample(now), self._centroid_at, velocity, arrive_s=approach.arrive_s)
            if again is not None:
                self._approach = approach = again
            else:
                drift = float(np.linalg.norm(self._centroid_at(approach.arrive_s) - approach.centroid_m))
                if drift > DRIFT_M:
                    self._stop()
                    return self.fail(INTERCEPT_MISSED, f"the fresh estimate puts the object {drift * 1000:.0f} mm from "
                                     "where the approach meets it and leaves no other intercept: it will have left the "
                                     "reach before a grasp could be over")
        t_cmd = now + self.dt / 2
        if t_cmd >= approach.arrive_s:
            self._phase, self._t_arrive = _DESCEND, approach.arrive_s
            self._blend = approach.centroid_m - self._centroid_at(approach.arrive_s)
            return self._match_step(now)
        state = approach.sample(t_cmd)
        self._command(state.q, state.qd)
        self.feedback_message = f"approach: intercept in {approach.arrive_s - now:.2f} s"
        return Status.RUNNING

    def _tool_pose(self, t_s: float) -> NDArray[np.float64]:
        """Where the tool must be at ``t_s`` in the ride (descend, close, lift)."""
        # deferred: pinocchio comes with it; a tree loads and validates without it
        from bt_grasp.motion.intercept import quintic, slowing

        s, grasp = self.settings, self._grasp
        assert grasp is not None
        tau = t_s - self._t_arrive
        lift_start = self._t_lift
        if lift_start is None:  # descending, then closing at the grasp
            rise = s.hover_m * (1.0 - quintic(tau / s.descend_s))
            blend = self._blend * (1.0 - quintic(tau / BLEND_S))
            return grasp.T_at(self._centroid_at(t_s) + blend, rise)
        tl = t_s - lift_start
        rise = self.ports.require("lift", float) * quintic(tl / s.lift_s)
        slow_from = lift_start + s.slow_after_s
        if t_s <= slow_from:
            return grasp.T_at(self._centroid_at(t_s), rise)
        p = self.track.predict(slow_from)
        centroid = p.position_m + p.velocity_m_s * slowing(t_s - slow_from, s.slow_s)
        return grasp.T_at(centroid, rise)

    def _match_step(self, now: float) -> Status:
        # deferred: pinocchio comes with it; a tree loads and validates without it
        from bt_grasp.motion.intercept import nearest_ik

        kin, robot, s = self.cell.kinematics, self.cell.robot, self.settings
        t_cmd = now + self.dt / 2
        T_now, T_next = self._tool_pose(t_cmd), self._tool_pose(t_cmd + self.dt)
        q = nearest_ik(kin, T_now, self._q_cmd)
        q_next = None if q is None else nearest_ik(kin, T_next, q)
        jump = float("inf") if q is None else float(np.max(np.abs(q - self._q_cmd)))
        if q is None or q_next is None or jump > MAX_STEP_RAD:
            self._stop()
            why = "no arm configuration reaches it" if q is None or q_next is None else \
                f"following it would turn a joint {jump:.2f} rad in one tick"
            return self.fail(INTERCEPT_MISSED, f"the arm cannot follow the object any further ({self._phase}): {why}")
        self._command(q, (q_next - q) / self.dt)
        tau = now - self._t_arrive
        if self._phase == _DESCEND and tau >= s.descend_s:
            robot.close_gripper(self.ports.require("force", float))
            self._phase, self._t_close, self._last_width, self._still = _CLOSE, now, robot.gripper_width_m(), 0
        elif self._phase == _CLOSE:
            return self._closing(now)
        elif self._phase == _LIFT and self._t_lift is not None and \
                now - self._t_lift >= max(s.lift_s, s.slow_after_s + s.slow_s):
            self._phase = _DONE
            self._finish(now)
            return Status.SUCCESS
        self.feedback_message = f"{self._phase}: {tau:.2f} s into the ride"
        return Status.RUNNING

    def _closing(self, now: float) -> Status:
        robot, s = self.cell.robot, self.settings
        width = robot.gripper_width_m()
        self._still = self._still + 1 if abs(width - self._last_width) < SETTLED_M else 0
        self._last_width = width
        waited = now - self._t_close
        if (self._still >= SETTLED_TICKS and waited >= MIN_CLOSE_S) or waited >= s.close_s:
            assert self._grasp is not None
            if width < empty_below_m(self._grasp.width_m):
                self._stop()
                return self.fail(FailureReason.GRASP_EMPTY, f"the fingers closed to {width * 1000:.1f} mm on nothing "
                                 "(the object was not where predicted)")
            self._phase, self._t_lift = _LIFT, now
            self._grasped_at = now
        self.feedback_message = f"closing: {width * 1000:.1f} mm"
        return Status.RUNNING

    def _finish(self, now: float) -> None:
        """The grasp as it closed and the object's detection there (for a Place that follows)."""
        # deferred: Open3D comes with it; a tree loads and validates without it
        from bt_grasp.perception.results import GraspCandidate

        assert self._grasp is not None
        t = self._grasped_at
        centroid = self._centroid_at(t)
        T_grasp = self._grasp.T_at(centroid)
        self.ports.set("grasp", GraspCandidate(T_grasp, T_grasp, self._grasp.width_m, 1.0, "intercepted on the belt"))
        self.ports.set("held", shifted(self.track.detection, centroid))
        self.feedback_message = f"lifted {self.ports.require('lift', float):.2f} m off the belt"

    # --- commanding the arm -------------------------------------------------------------------------------------
    def _command(self, q: NDArray[np.float64], qd: NDArray[np.float64]) -> None:
        self.cell.robot.set_joint_targets(q, qd)
        self._q_cmd = np.asarray(q, dtype=float).copy()

    def _stop(self) -> None:
        """Bring the arm to rest smoothly: hold where it would be after decelerating over STOP_TIME_S."""
        robot = self.cell.robot
        q, qd = robot.joint_positions(), robot.joint_velocities()
        robot.set_joint_targets(q + qd * (STOP_TIME_S / 2), np.zeros_like(q))

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.IDLE and getattr(self, "_approach", None) is not None:
            self._stop()

    def _record(self, now: float) -> None:
        p = self.track.predict(now)
        tcp = self.cell.kinematics.fk(self.cell.robot.joint_positions())[:3, 3]
        values: dict[str, float | bool | str] = {
            "t_s": now, "phase": self._phase, "detections": float(self.track.detections),
            "target_x_m": float(p.position_m[0]), "target_y_m": float(p.position_m[1]),
            "target_z_m": float(p.position_m[2]), "target_along_m": p.along_m, "sigma_m": p.sigma_m,
            "target_vx_m_s": float(p.velocity_m_s[0]), "target_vy_m_s": float(p.velocity_m_s[1]),
            "tcp_x_m": float(tcp[0]), "tcp_y_m": float(tcp[1]), "tcp_z_m": float(tcp[2]),
        }
        if self._approach is not None:
            values["arrive_s"] = self._approach.arrive_s
        self.cell.media.servo(self.name, values)


def shifted(det: Detection, centroid_m: NDArray[np.float64]) -> Detection:
    """The detection moved (without turning) so that its centroid is ``centroid_m``: where the belt carried it."""
    d = np.asarray(centroid_m, dtype=float) - np.asarray(det.centroid_base_m, dtype=float)
    points = None if det.points_base_m is None else np.asarray(det.points_base_m) + d
    obb = None if det.obb is None else replace(det.obb, center_m=tuple(np.asarray(det.obb.center_m) + d))
    obb_pca = None if det.obb_pca is None else replace(det.obb_pca,
                                                       center_m=tuple(np.asarray(det.obb_pca.center_m) + d))
    return replace(det, centroid_base_m=(float(centroid_m[0]), float(centroid_m[1]), float(centroid_m[2])),
                   footprint_base_m=tuple((x + d[0], y + d[1]) for x, y in det.footprint_base_m),
                   points_base_m=points, obb=obb, obb_pca=obb_pca)
