"""A Robotiq 2F-85 as its URCap's socket (port 63352) shows it: registers in, status out, the fingers in physics.

Registers a client writes (``SET``): ``ACT`` (1 activates, 0 resets), ``GTO`` (1 goes to the requested position),
``POS`` (0 open .. 255 closed), ``SPE`` (0 .. 255 speed), ``FOR`` (0 .. 255 force), ``ATR``/``ARD`` (automatic
release: acknowledged, not simulated). Status it reads (``GET``): ``STA`` (0 reset, 1 activating, 3 active),
``OBJ`` (0 moving, 1 stopped on an object while opening, 2 while closing, 3 at the requested position), ``FLT``
(0: no fault), ``POS`` (where the fingers are), ``PRE`` (the position request echoed once taken).

Like the real gripper, the fingers' full travel is about 3 .. 230 counts, not 0 .. 255 (the 2F-85's pads touch
before the screw's end): a request below 3 opens fully and one above 230 closes until the pads meet something,
pressing with the force ``FOR`` sets. Activation takes :data:`ACTIVATION_S` and moves nothing (the real gripper
opens and closes once to find its stroke).
"""

from __future__ import annotations

import threading
from typing import Protocol

from bt_grasp.cell.grippers import GripperModel

POS_OPEN = 3  # counts at full opening
POS_CLOSED = 230  # counts with the pads together
ACTIVATION_S = 0.5
#: the fingers count as stopped below this opening speed (m/s) ...
STALL_SPEED_M_S = 0.002
#: ... for this long after the commanded opening stopped changing (or while it still moves, on contact)
STALL_S = 0.05
#: within this many counts of the request the fingers are "at the requested position"
AT_POSITION_COUNTS = 2
READABLE = ("ACT", "GTO", "STA", "OBJ", "FLT", "POS", "PRE", "SPE", "FOR", "ATR", "ARD")
WRITABLE = ("ACT", "GTO", "POS", "SPE", "FOR", "ATR", "ARD")


class FingerDrive(Protocol):
    """What the device moves: the simulated fingers' opening."""

    def set_opening_target(self, width_m: float, force_n: float) -> None:
        """Drive the pads toward ``width_m`` apart (negative: beyond closed) pressing with at most ``force_n``."""
        ...

    def opening_m(self) -> float: ...


class Robotiq2F85:
    """The gripper's register logic, stepped by the controller's cycle; ``set``/``get`` from the socket thread."""

    def __init__(self, model: GripperModel, drive: FingerDrive) -> None:
        self.model = model
        self.drive = drive
        self._lock = threading.Lock()
        self.regs = {"ACT": 0, "GTO": 0, "POS": 0, "SPE": 255, "FOR": 150, "ATR": 0, "ARD": 0}
        self.sta = 0
        self.obj = 0
        self.pre = 0
        self._activation_left_s = 0.0
        self._command_m = drive.opening_m()  # the opening the speed ramp has reached
        self._goal_m = self._command_m
        self._stalled_s = 0.0
        self._moving = False
        self._last_width_m = self._command_m

    # --- counts <-> metres ------------------------------------------------------------------------------
    def counts_to_opening_m(self, counts: int) -> float:
        c = min(max(counts, POS_OPEN), POS_CLOSED)
        return self.model.stroke_m * (POS_CLOSED - c) / (POS_CLOSED - POS_OPEN)

    def opening_to_counts(self, width_m: float) -> int:
        c = POS_CLOSED - width_m / self.model.stroke_m * (POS_CLOSED - POS_OPEN)
        return round(min(max(c, POS_OPEN), POS_CLOSED))

    def speed_m_s(self) -> float:
        lo, hi = self.model.speed_range_m_s
        return lo + (hi - lo) * self.regs["SPE"] / 255

    def force_n(self) -> float:
        lo, hi = self.model.force_range_n
        return lo + (hi - lo) * self.regs["FOR"] / 255

    # --- the socket's side ------------------------------------------------------------------------------
    def set(self, assignments: list[tuple[str, int]]) -> None:
        """One ``SET`` line's assignments, applied together (names from :data:`WRITABLE`, values 0..255)."""
        with self._lock:
            for name, value in assignments:
                self.regs[name] = value
            if self.regs["ACT"] == 0:
                self.sta, self.obj, self.pre, self._moving = 0, 0, 0, False
                self.regs["GTO"] = 0
            elif self.sta == 0:
                self.sta = 1
                self._activation_left_s = ACTIVATION_S
            if self.sta == 3 and self.regs["GTO"] == 1 and any(n in ("POS", "GTO", "SPE", "FOR")
                                                                for n, _ in assignments):
                self._start_move()

    def get(self, name: str) -> int:
        with self._lock:
            if name == "STA":
                return self.sta
            if name == "OBJ":
                return self.obj
            if name == "FLT":
                return 0
            if name == "PRE":
                return self.pre
            if name == "POS":
                return self.opening_to_counts(self.drive.opening_m())
            return self.regs[name]

    # --- the controller's cycle -------------------------------------------------------------------------
    def _start_move(self) -> None:
        self.pre = self.regs["POS"]
        request = self.regs["POS"]
        self._goal_m = -0.02 if request >= POS_CLOSED else self.counts_to_opening_m(request)
        self._moving = True
        self._stalled_s = 0.0
        self._command_m = self._last_width_m = self.drive.opening_m()  # the ramp starts where the fingers are
        self.obj = 0

    def step(self, dt: float) -> None:
        with self._lock:
            if self.sta == 1:
                self._activation_left_s -= dt
                if self._activation_left_s <= 0:
                    self.sta = 3
                return
            if self.sta != 3 or not self._moving:
                return
            # ramp the commanded opening toward the goal at the set speed
            step = self.speed_m_s() * dt
            goal, command = self._goal_m, self._command_m
            command = min(goal, command + step) if goal > command else max(goal, command - step)
            ramping = command != self._command_m
            self._command_m = command
            self.drive.set_opening_target(command, self.force_n())
            width = self.drive.opening_m()
            # the change over the cycle, not the joint's reported speed (against a limit PhysX reports a speed)
            still = abs(width - self._last_width_m) < STALL_SPEED_M_S * dt
            self._last_width_m = width
            behind = abs(command - width) > 0.002
            self._stalled_s = self._stalled_s + dt if still and (behind or not ramping) else 0.0
            if self._stalled_s < STALL_S:
                return
            self._moving = False
            counts = self.opening_to_counts(width)
            request = self.regs["POS"]
            if abs(counts - min(max(request, POS_OPEN), POS_CLOSED)) <= AT_POSITION_COUNTS:
                self.obj = 3
            else:
                self.obj = 2 if goal < width else 1
