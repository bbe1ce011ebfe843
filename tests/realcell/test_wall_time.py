"""Time on a real cell is wall time, in one place: the stepper keeps the controller's period, polls the cell once
a period (before the first tick too), and trajectory time follows the speed slider and never jumps after a late
tick."""

from __future__ import annotations

import time

import pytest

from bt_grasp.hardware import wall_time
from bt_grasp.hardware.wall_time import CellStepper, WallClock


class _VirtualTime:
    """``time`` for the stepper, on a clock that only ``sleep`` (and ``late``) advance: the arithmetic of trajectory
    time checked exactly, whatever the machine's load (on the wall clock a loaded machine oversleeps, and each
    late period gives the motion less than a period, which is the behaviour, not a flake)."""

    def __init__(self) -> None:
        self.ns = 1_000_000_000

    def monotonic(self) -> float:
        return self.ns / 1e9

    def monotonic_ns(self) -> int:
        return self.ns

    def sleep(self, seconds: float) -> None:
        self.ns += round(seconds * 1e9)


def test_steps_keep_the_period_on_the_wall_clock() -> None:
    polls: list[float] = []

    def poll(stalled_s: float) -> float:
        polls.append(stalled_s)
        return 1.0

    stepper = CellStepper(WallClock(), 0.008, poll)
    stepper.restart()
    start = time.monotonic()
    stepper.step(25)
    elapsed = time.monotonic() - start
    # never faster than the period; the upper bound is generous: a loaded 2-core machine oversleeps
    assert 0.19 <= elapsed < 2.0 and len(polls) == 25
    assert 0 < stepper.motion_clock.now_ns() <= 0.2e9 + 1  # at most one period of trajectory time a period


def test_trajectory_time_follows_the_slider(monkeypatch: pytest.MonkeyPatch) -> None:
    virtual = _VirtualTime()
    monkeypatch.setattr(wall_time, "time", virtual)
    scaling = [1.0]
    stepper = CellStepper(WallClock(), 0.008, lambda stalled_s: scaling[0])
    stepper.restart()
    stepper.step(25)
    assert stepper.motion_clock.now_ns() == 200_000_000 and virtual.ns == 1_200_000_000
    scaling[0] = 0.5
    stepper.step(25)
    assert stepper.motion_clock.now_ns() == 300_000_000  # the slider at 50 %: half the time
    scaling[0] = 1.0
    virtual.sleep(0.1)  # a tick that took 100 ms: the motion gets one period, no jump, and an overrun is counted
    stepper.step()
    assert stepper.motion_clock.now_ns() == 308_000_000 and stepper.overruns == 1


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
