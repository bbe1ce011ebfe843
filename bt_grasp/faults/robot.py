"""A robot wrapper whose controller a fault can stall (arm targets ignored) or hang (every command ignored)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from bt_grasp.clock import Clock
from bt_grasp.faults.armed import ArmedFault
from bt_grasp.interfaces import Robot


@dataclass
class _Window:
    arming: ArmedFault
    until_ns: int
    gripper_too: bool  # a hang also ignores gripper commands; a stall only the arm's


class FaultyRobot:
    """Implements :class:`bt_grasp.interfaces.Robot` around the real one.

    While a stall or hang window is open, ``set_joint_targets`` is not passed on: the joint drives keep
    the last target they received, exactly what a controller that stopped following its command stream
    does. Measurements always come from the real robot.
    """

    def __init__(self, inner: Robot, clock: Clock) -> None:
        self.inner = inner
        self.clock = clock
        self._windows: list[_Window] = []

    def hold(self, arming: ArmedFault, duration_s: float, gripper_too: bool = False) -> None:
        self._windows.append(_Window(arming, self.clock.now_ns() + round(duration_s * 1e9), gripper_too))

    def _blocking(self, gripper: bool) -> _Window | None:
        now = self.clock.now_ns()
        for window in self._windows:
            if now >= window.until_ns:
                window.arming.finish()
        self._windows = [w for w in self._windows if not w.arming.done]
        for window in self._windows:
            if window.gripper_too or not gripper:
                return window
        return None

    # --- measurements: always the real robot's ---------------------------------------------------------
    @property
    def joint_names(self) -> tuple[str, ...]:
        return self.inner.joint_names

    def joint_positions(self) -> NDArray[np.float64]:
        return self.inner.joint_positions()

    def joint_velocities(self) -> NDArray[np.float64]:
        return self.inner.joint_velocities()

    def gripper_width_m(self) -> float:
        return self.inner.gripper_width_m()

    def gripper_target_width_m(self) -> float:
        return self.inner.gripper_target_width_m()

    # --- commands: swallowed while blocked -----------------------------------------------------------------
    def set_joint_targets(self, q_rad: NDArray[np.float64], qd_rad_s: NDArray[np.float64] | None = None) -> None:
        window = self._blocking(gripper=False)
        if window is None:
            self.inner.set_joint_targets(q_rad, qd_rad_s)
            return
        window.arming.fire(effect="arm targets ignored", until_ns=window.until_ns)

    def open_gripper(self) -> None:
        window = self._blocking(gripper=True)
        if window is None:
            self.inner.open_gripper()
            return
        window.arming.fire(effect="gripper command ignored", until_ns=window.until_ns)

    def close_gripper(self, force_n: float | None = None) -> None:
        window = self._blocking(gripper=True)
        if window is None:
            self.inner.close_gripper(force_n)
            return
        window.arming.fire(effect="gripper command ignored", until_ns=window.until_ns)

    def expire(self) -> None:
        """Close windows whose time has passed (called once per tick)."""
        self._blocking(gripper=True)
