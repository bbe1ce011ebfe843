"""Time on a real cell is wall time, in one place: the stepper keeps the controller's period, polls the cell once
a period (before the first tick too), and trajectory time follows the speed slider and never jumps after a late
tick."""

from __future__ import annotations

import time

import pytest

from bt_grasp.hardware.wall_time import CellStepper, WallClock


def test_steps_keep_the_period_and_trajectory_time_follows_the_slider() -> None:
    scaling = [1.0]
    polls: list[float] = []

    def poll(stalled_s: float) -> float:
        polls.append(stalled_s)
        return scaling[0]

    stepper = CellStepper(WallClock(), 0.008, poll)
    stepper.restart()
    start = time.monotonic()
    stepper.step(25)
    elapsed = time.monotonic() - start
    assert 0.19 <= elapsed < 0.6 and len(polls) == 25  # 25 periods of 8 ms (a busy machine may be late)
    at_full = stepper.motion_clock.now_ns()
    assert 0.18e9 < at_full <= 0.2e9 + 1  # at most one period of trajectory time a period
    scaling[0] = 0.5
    stepper.step(25)
    assert 0.09e9 < stepper.motion_clock.now_ns() - at_full <= 0.1e9 + 1  # the slider at 50 %: half the time


def test_a_late_tick_slows_the_motion_instead_of_making_it_jump() -> None:
    stepper = CellStepper(WallClock(), 0.008, lambda stalled_s: 1.0)
    stepper.restart()
    stepper.step()
    before = stepper.motion_clock.now_ns()
    time.sleep(0.1)  # a tick that took 100 ms
    stepper.step()
    assert stepper.motion_clock.now_ns() - before <= 8_000_000 + 1
    assert stepper.overruns >= 1


def test_a_fault_raised_by_the_poll_reaches_the_tick_loop() -> None:
    def poll(stalled_s: float) -> float:
        raise RuntimeError("the cell ended the run")

    stepper = CellStepper(WallClock(), 0.008, poll)
    with pytest.raises(RuntimeError, match="the cell ended the run"):
        stepper.step()
