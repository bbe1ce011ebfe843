"""Safety before motion (issue 41, done-when 3's last clause): a trajectory outside the workspace box, under the
table or beyond a joint's range is refused whole before anything is sent; one over the caps is slowed to them (never
sped up); a streamed target is checked again, step by step."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_grasp.cell.format import load_cell
from bt_grasp.cell.grippers import ROBOTIQ_2F85, robot_urdf_path_with
from bt_grasp.episode.cell_devices import guard_for
from bt_grasp.motion.guard import MotionGuard
from bt_grasp.motion.kinematics import ArmKinematics
from bt_grasp.motion.trajectory import MotionLimits, Trajectory, time_parametrize

REPO = Path(__file__).resolve().parents[2]
HOME = np.array(load_cell(REPO / "cells" / "example-ur5.yaml").arm.home_q_rad)


@pytest.fixture(scope="module")
def kin() -> ArmKinematics:
    return ArmKinematics(urdf_path=robot_urdf_path_with(ROBOTIQ_2F85.name))


@pytest.fixture(scope="module")
def guard(kin: ArmKinematics) -> MotionGuard:
    return guard_for(load_cell(REPO / "cells" / "example-ur5.yaml"), kin)


def _to(kin: ArmKinematics, xyz: tuple[float, float, float], limits: MotionLimits | None = None) -> Trajectory:
    T = kin.fk(HOME)
    T[:3, 3] = xyz
    found = kin.ik(T, HOME)
    assert found.ok
    return time_parametrize(np.array([HOME, found.q]), limits or MotionLimits(0.5, 1.0), rate_hz=125.0)


def test_a_trajectory_inside_the_box_and_under_the_caps_passes_unchanged(guard: MotionGuard, kin: ArmKinematics
                                                                          ) -> None:
    trajectory = _to(kin, (0.45, 0.1, 0.2))
    assert guard.prepare(trajectory) is trajectory


@pytest.mark.parametrize(("xyz", "why"), [
    ((0.35, 0.1, 0.52), "the TCP would leave the workspace box"),  # above the box
    ((0.45, -0.45, 0.2), "the TCP would leave the workspace box"),  # beside it
    ((0.45, 0.1, 0.01), "the finger tips would go "),  # the TCP in the box (z 1 cm), the tips 2 cm beyond it
])
def test_a_trajectory_leaving_the_box_or_going_under_the_table_is_refused(guard: MotionGuard, kin: ArmKinematics,
                                                                           xyz: tuple[float, float, float],
                                                                           why: str) -> None:
    refused = guard.prepare(_to(kin, xyz))
    assert isinstance(refused, str) and refused.startswith(why), refused


def test_a_joint_beyond_its_range_is_refused(guard: MotionGuard, kin: ArmKinematics) -> None:
    trajectory = _to(kin, (0.45, 0.1, 0.2))
    q = trajectory.q.copy()
    q[-1, 5] = kin.upper_rad[5] + 0.01
    refused = guard.prepare(Trajectory(trajectory.times_s, q, trajectory.qd, trajectory.qdd))
    assert isinstance(refused, str) and "joint 6 would go to" in refused


def test_a_trajectory_over_the_caps_is_slowed_to_them(guard: MotionGuard, kin: ArmKinematics) -> None:
    fast = _to(kin, (0.6, -0.2, 0.25), MotionLimits(2.0, 6.0))
    slowed = guard.prepare(fast)
    assert isinstance(slowed, Trajectory) and slowed.duration_s > fast.duration_s
    assert np.max(np.abs(slowed.qd)) <= 0.5 and np.max(np.abs(slowed.qdd)) <= 1.0
    p = np.array([kin.fk(q)[:3, 3] for q in slowed.q])
    speed = np.linalg.norm(np.diff(p, axis=0), axis=1) / np.diff(slowed.times_s)
    assert float(np.max(speed)) <= 0.25
    assert np.array_equal(slowed.q, fast.q)  # the same path, only slower


def test_a_streamed_target_is_checked_again(guard: MotionGuard) -> None:
    step = 0.5 / 125.0  # the speed cap's travel in one period
    assert guard.check_target(HOME + step, HOME, HOME) is None
    jump = guard.check_target(HOME + 0.05, HOME, HOME)
    assert jump is not None and "more than the speed cap allows in one period" in jump
    assert guard.check_target(HOME + 0.05, HOME, HOME + 0.05) is None  # where the arm is: a hold, always allowed
    assert "not six finite" in (guard.check_target(np.full(6, np.nan), HOME, HOME) or "")


def test_a_trajectory_over_the_caps_is_refused_by_the_check(guard: MotionGuard, kin: ArmKinematics) -> None:
    fast = _to(kin, (0.6, -0.2, 0.25), MotionLimits(2.0, 6.0))
    problem = guard.check(fast)
    assert problem is not None and "over the cap" in problem
    slow = guard.fit(fast)
    assert isinstance(slow, Trajectory) and guard.check(slow) is None
