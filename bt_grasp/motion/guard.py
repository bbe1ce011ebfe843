"""Safety before motion: every trajectory a real cell's leaves would send is checked whole before its first sample
leaves, and every streamed target again as it leaves.

The limits are the cell file's (``bt_grasp.cell.format``): the joints' limits (the robot description's), the joint
speed and acceleration caps, the tool speed cap, the workspace box the TCP must stay in, and the table top the finger
tips must stay above. :meth:`MotionGuard.prepare` slows a trajectory (never speeds it up) until it is within the three
caps, then checks every sample; anything else wrong (a joint out of its range, the TCP outside the box, the finger
tips under the table) refuses it with one sentence, and nothing is sent; :meth:`MotionGuard.check` refuses a
trajectory over any cap too (a leaf's trajectory is fitted to them first). :meth:`MotionGuard.check_target` checks one
streamed target: within the joint limits, the TCP in the box and above the table, and not farther from the last
target (or from where the arm is) than the speed cap allows in one control period.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from bt_grasp.motion.trajectory import Trajectory

Vec = NDArray[np.float64]

#: a trajectory is slowed to this fraction of the tool speed cap (the speed between samples, measured along chords,
#: is a little under the speed along the arc); the joints' samples are ruckig's own, and the caps are theirs
CAP_MARGIN = 0.98
#: a streamed target may step this many times the speed cap's travel in one period (and JUMP_SLACK_RAD more)
STEP_SLACK = 1.25
STEP_SLACK_RAD = 1e-4
#: joint positions within this of a limit count as inside it (rounding of a limit sample)
LIMIT_SLACK_RAD = 1e-6


class ToolKinematics(Protocol):
    """The arm's forward kinematics to the TCP (``bt_grasp.motion.kinematics.ArmKinematics``)."""

    @property
    def lower_rad(self) -> Vec: ...

    @property
    def upper_rad(self) -> Vec: ...

    def fk(self, q: Vec) -> Vec: ...


@dataclass(frozen=True)
class GuardLimits:
    """The cell's limits, base frame, metres, radians, seconds."""

    joint_speed_cap_rad_s: float
    joint_accel_cap_rad_s2: float
    tool_speed_cap_m_s: float
    box_min_m: tuple[float, float, float]
    box_max_m: tuple[float, float, float]
    table_z_m: float  # the table top's height
    tcp_to_fingertip_m: float  # the finger tips lie this far along the TCP's z
    period_s: float  # the controller's period (one streamed target each)


class MotionGuard:
    """See the module docstring. ``kin``: the planning model of the cell's arm and gripper (its TCP)."""

    def __init__(self, limits: GuardLimits, kin: ToolKinematics) -> None:
        self.limits = limits
        self.kin = kin
        self._lower = np.asarray(kin.lower_rad, dtype=float) - LIMIT_SLACK_RAD
        self._upper = np.asarray(kin.upper_rad, dtype=float) + LIMIT_SLACK_RAD
        self._box_min = np.asarray(limits.box_min_m, dtype=float)
        self._box_max = np.asarray(limits.box_max_m, dtype=float)
        #: trajectories refused and targets refused since the cell was made (the run's result reports them)
        self.refused = 0

    # -- whole trajectories ---------------------------------------------------------------------------------------
    def prepare(self, trajectory: Trajectory) -> Trajectory | str:
        """The trajectory fitted to the caps (:meth:`fit`) and checked (:meth:`check`), or why it is refused (one
        sentence): nothing of a refused trajectory may be sent."""
        fitted = self.fit(trajectory)
        if isinstance(fitted, str):
            return self._refuse(fitted)
        problem = self.check(fitted)
        return fitted if problem is None else self._refuse(problem)

    def fit(self, trajectory: Trajectory) -> Trajectory | str:
        """The same path slowed (never sped up) until it is within the joint and tool speed caps and the joint
        acceleration cap; a trajectory that is not finite joint samples is a sentence."""
        q = np.asarray(trajectory.q, dtype=float)
        if q.ndim != 2 or q.shape[1] != 6 or len(q) == 0 or not np.all(np.isfinite(q)):
            return "the trajectory is not finite joint samples"
        lim = self.limits
        qd = float(np.max(np.abs(trajectory.qd))) if len(trajectory.qd) else 0.0
        qdd = float(np.max(np.abs(trajectory.qdd))) if len(trajectory.qdd) else 0.0
        joint = max(qd / lim.joint_speed_cap_rad_s, float(np.sqrt(qdd / lim.joint_accel_cap_rad_s2)))
        tool = self._tool_speed(trajectory) / (lim.tool_speed_cap_m_s * CAP_MARGIN)
        scale = max(1.0, tool, joint if joint > 1.0 + 1e-9 else 1.0)
        return _stretched(trajectory, scale) if scale > 1.0 else trajectory

    def check(self, trajectory: Trajectory) -> str | None:
        """Why the trajectory may not be sent (one sentence), or None: every sample within the joints' limits, the
        TCP inside the workspace box, the finger tips above the table, the joint speeds, accelerations and the
        tool's speed within the caps."""
        q = np.asarray(trajectory.q, dtype=float)
        if q.ndim != 2 or q.shape[1] != 6 or len(q) == 0 or not np.all(np.isfinite(q)):
            return "the trajectory is not finite joint samples"
        problem = self._joint_problem(q)
        if problem is not None:
            return problem
        for k, qk in enumerate(q):
            problem = self._pose_problem(self.kin.fk(qk))
            if problem is not None:
                return f"{problem} (sample {k} of {len(q)})"
        lim = self.limits
        qd = float(np.max(np.abs(trajectory.qd))) if len(trajectory.qd) else 0.0
        if qd > lim.joint_speed_cap_rad_s * (1 + 1e-9):
            return f"a joint would move at {qd:.3f} rad/s, over the cap {lim.joint_speed_cap_rad_s:g} rad/s"
        qdd = float(np.max(np.abs(trajectory.qdd))) if len(trajectory.qdd) else 0.0
        if qdd > lim.joint_accel_cap_rad_s2 * (1 + 1e-9):
            return (f"a joint would accelerate at {qdd:.3f} rad/s^2, over the cap {lim.joint_accel_cap_rad_s2:g} "
                    "rad/s^2")
        tool = self._tool_speed(trajectory)
        if tool > lim.tool_speed_cap_m_s * CAP_MARGIN * (1 + 1e-9):
            return f"the TCP would move at {tool:.3f} m/s, over the cap {lim.tool_speed_cap_m_s:g} m/s"
        return None

    def _tool_speed(self, trajectory: Trajectory) -> float:
        """The TCP's largest speed between samples (along chords), m/s."""
        times = np.asarray(trajectory.times_s, dtype=float)
        if len(times) < 2:
            return 0.0
        p = np.array([self.kin.fk(qk)[:3, 3] for qk in trajectory.q])
        dt = np.diff(times)
        moving = dt > 0
        if not np.any(moving):
            return 0.0
        return float(np.max(np.linalg.norm(np.diff(p, axis=0)[moving], axis=1) / dt[moving]))

    def _joint_problem(self, q: Vec) -> str | None:
        low = q < self._lower
        high = q > self._upper
        if np.any(low | high):
            k, j = np.argwhere(low | high)[0]
            side = "lower" if low[k, j] else "upper"
            limit = self._lower[j] if low[k, j] else self._upper[j]
            return (f"joint {j + 1} would go to {q[k, j]:.3f} rad, beyond its {side} limit {limit:.3f} rad "
                    f"(sample {k})")
        return None

    def _pose_problem(self, T: Vec) -> str | None:
        p = T[:3, 3]
        lim = self.limits
        if np.any(p < self._box_min) or np.any(p > self._box_max):
            return (f"the TCP would leave the workspace box at ({p[0]:.3f}, {p[1]:.3f}, {p[2]:.3f}) m "
                    f"(the box: {_xyz(lim.box_min_m)} to {_xyz(lim.box_max_m)})")
        tips = p + T[:3, 2] * lim.tcp_to_fingertip_m
        lowest = min(float(p[2]), float(tips[2]))
        if lowest < lim.table_z_m:
            return (f"the finger tips would go {(lim.table_z_m - lowest) * 1000:.1f} mm under the table top "
                    f"(z {lim.table_z_m:.3f} m)")
        return None

    # -- streamed targets -------------------------------------------------------------------------------------------
    def check_target(self, q: Vec, last_target: Vec | None, measured: Vec) -> str | None:
        """Why one streamed target may not be sent, or None."""
        q = np.asarray(q, dtype=float).reshape(-1)
        if q.shape != (6,) or not np.all(np.isfinite(q)):
            return self._refuse("a target that is not six finite joint angles")
        problem = self._joint_problem(q[None, :]) or self._pose_problem(self.kin.fk(q))
        if problem is not None:
            return self._refuse(problem)
        step = self.limits.joint_speed_cap_rad_s * self.limits.period_s * STEP_SLACK + STEP_SLACK_RAD
        from_last = float(np.max(np.abs(q - last_target))) if last_target is not None else np.inf
        from_arm = float(np.max(np.abs(q - np.asarray(measured, dtype=float))))
        if min(from_last, from_arm) > step:
            return self._refuse(f"a target {min(from_last, from_arm):.4f} rad from the last one and from the arm: "
                                f"more than the speed cap allows in one period ({step:.4f} rad)")
        return None

    def _refuse(self, sentence: str) -> str:
        self.refused += 1
        return sentence


def _stretched(trajectory: Trajectory, scale: float) -> Trajectory:
    """The same path ``scale`` times slower (times x scale, speeds / scale, accelerations / scale^2)."""
    return dataclasses.replace(trajectory, times_s=np.asarray(trajectory.times_s) * scale,
                               qd=np.asarray(trajectory.qd) / scale, qdd=np.asarray(trajectory.qdd) / scale**2)


def _xyz(v: tuple[float, float, float]) -> str:
    return f"({v[0]:.3f}, {v[1]:.3f}, {v[2]:.3f})"
