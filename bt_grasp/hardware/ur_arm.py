"""``UrArm``: the :class:`bt_grasp.interfaces.Robot` of a UR arm through ur_rtde, with a Robotiq 2F-85 as its gripper.

A thin adapter, as ur_rtde's own examples drive a UR:

* **Motion** is streamed with ``servoJ`` at the controller's period (8 ms on a CB3): each target the executor sets
  (a sample of a ruckig trajectory the cell's :class:`~bt_grasp.motion.guard.MotionGuard` checked whole
  before its first sample) is checked again (:meth:`MotionGuard.check_target`) and sent; a target that fails is not
  sent, the arm is stopped and the run ends ``SAFETY_LIMIT``. The controller's servo thread holds the last target
  when no new one comes. ``lookahead_time`` 0.1 s and ``gain`` 300 are ur_rtde's example values.
* **State** is the controller's: joint positions and speeds from ``RTDEReceiveInterface`` (``actual_q``,
  ``actual_qd``), and each period (:meth:`poll`, from the tick loop) the robot mode, safety status bits, runtime state,
  the connection and the speed scaling; any of them ending the run is a typed
  :class:`~bt_grasp.hardware.cell_faults.CellFault` (``fault_from_state``), after the arm is stopped.
* **The watchdog** (``rtde_set_watchdog`` through ur_rtde's ``setWatchdog``) is kicked from the tick loop: every
  ``servoJ`` writes its register, and :meth:`poll` kicks it in periods that sent none. While moving targets stream
  (a trajectory's samples on their way) it asks for :data:`WATCHDOG_MOTION_HZ` (a process stalled mid-motion stops
  the program within 0.25 s; the servo holding its last target has stood the arm still before that); a hold (a
  target with no velocity: a trajectory's last sample, a settling or cancelled motion) relaxes it to
  :data:`WATCHDOG_HOLD_HZ` at once (the tick that ends a motion may go on to perceive or plan for a few hundred ms
  while the servo holds the arm still: a stall then moves nothing). A stall the watchdog ended is reported
  ``WATCHDOG``: a gap in the writes to its register longer than it allowed, then a stopped program.
* **A controller that went away**: ur_rtde's synchronous calls would wait for it (and try to reconnect, for
  seconds), so each runs in a thread of its own with a bound (:data:`SYNC_TIMEOUT_S`), and nothing synchronous goes
  to a controller whose state stopped coming (no new RTDE timestamp for :data:`LOST_AFTER_S`): ``CONNECTION_LOST``.
* **The first motion** waits for ``confirm`` (the operator's yes; ``--yes`` skips it); the watchdog is armed then,
  not before (a prompt may wait longer than any watchdog).
* **Stops**: :meth:`stop` sends ``stopJ`` (the Ctrl-C path and every fault's); after a fault the arm takes no more
  commands.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from bt_grasp.cell.format import Arm
from bt_grasp.hardware.cell_faults import (
    CellFault,
    CellFaultKind,
    CellUnavailable,
    ControllerState,
    fault_from_state,
)
from bt_grasp.hardware.device_objects import RtdeObject
from bt_grasp.hardware.robotiq_client import Robotiq2F85Client
from bt_grasp.hardware.ur_lib import ur_rtde
from bt_grasp.robot_description import ARM_JOINTS

log = logging.getLogger(__name__)

SERVO_LOOKAHEAD_S = 0.1
SERVO_GAIN = 300.0
#: the watchdog while targets stream: the program stops 0.25 s after the last write. The arm itself stops sooner: the
#: controller's servo holds the last target, so a stalled stream stands the arm still within a few periods; the
#: watchdog ends the program (a loaded 2-core machine stalled a tick loop of normal priority past 0.1 s mid-motion)
WATCHDOG_MOTION_HZ = 4.0
#: the watchdog while the arm holds: perceiving (a camera's frame may take its 1 s timeout) and planning on a busy
#: machine may take seconds between ticks, and a stall then moves nothing
WATCHDOG_HOLD_HZ = 0.2
#: a stream of moving targets that stopped without a hold counts as a hold after this long
HOLD_AFTER_S = 0.05
HOLD_SPEED_RAD_S = 0.01
#: the controller's state (its RTDE timestamp) not advancing for this long while the tick loop runs is a lost
#: connection (a controller sends it every period: 8 ms on a CB3)
LOST_AFTER_S = 0.1
#: a synchronous ur_rtde command (the watchdog, the TCP) not answered within this is a lost connection; a stop within
#: STOP_TIMEOUT_S (it returns once the arm stands still)
SYNC_TIMEOUT_S = 0.5
#: after a stall of this process, the state is read again once it is this recent (at most this long a wait), and a
#: stopped program seen within RECENT_STALL_S of it is the watchdog's doing when the stall outlasted the watchdog
CATCH_UP_S = 0.3
RECENT_STALL_S = 1.0
STOP_TIMEOUT_S = 1.5
#: how fast a stop (a fault, Ctrl-C) decelerates the joints (rad/s^2; ur_rtde's stopJ default is 2: a stop is quicker)
STOP_DECEL_RAD_S2 = 10.0


class TargetGuard(Protocol):
    """What the arm asks of the cell's guard (:class:`bt_grasp.motion.guard.MotionGuard`, given by the composition
    in ``bt_grasp.episode.cell_devices``: the hardware package plans and checks nothing itself)."""

    def check_target(self, q: NDArray[np.float64], last_target: NDArray[np.float64] | None,
                     measured: NDArray[np.float64]) -> str | None: ...


class UrArm:
    """Implements :class:`bt_grasp.interfaces.Robot` (see the module docstring). :meth:`connect` before use."""

    def __init__(self, arm: Arm, gripper: Robotiq2F85Client, guard: TargetGuard) -> None:
        self.arm = arm
        self.gripper = gripper
        self.guard = guard
        self.period_s = 1.0 / arm.control_rate_hz
        self.control: RtdeObject = None
        self.receive: RtdeObject = None
        self.stopped_by: CellFault | None = None
        self._last_target: NDArray[np.float64] | None = None
        self._target_since = time.monotonic()
        self._sent_since_poll = False
        self._watchdog_hz = 0.0
        self._servoing = False
        #: asked before the first motion (None: not asked); False ends the run NOT_CONFIRMED with nothing sent
        self.confirm: Callable[[], bool] | None = None
        self.moved = False
        self._stamp = -1.0  # the controller's last RTDE timestamp seen, and until when a new one must come
        self._stamp_deadline = math.inf
        self.lost = False  # no state came from the controller: nothing more is sent (a command would wait for it)
        self._written_at = time.monotonic()  # the watchdog's register was last written (a servoJ, a kick)
        self._missed = (0.0, 0.0, -math.inf)  # the last gap the watchdog did not allow: its length, its Hz, its end

    # -- life -----------------------------------------------------------------------------------------------------
    def connect(self) -> None:
        """Connect RTDE, upload ur_rtde's control script, set the TCP, payload and watchdog, connect the gripper.
        :class:`CellUnavailable` (one sentence) when the cell cannot be used; nothing has moved then."""
        rtde_control, rtde_receive = ur_rtde("a UR arm")
        host = self.arm.address
        try:
            self.receive = rtde_receive.RTDEReceiveInterface(host)
        except RuntimeError as exc:
            raise CellUnavailable(f"the controller at {host} does not answer RTDE (port 30004): {exc}") from None
        before = fault_from_state(self._state(script=False))
        if before is not None:
            self.close()
            raise CellUnavailable(f"the robot at {host} is not ready: {before.detail}")
        try:
            self.control = rtde_control.RTDEControlInterface(host)
        except RuntimeError as exc:
            self.close()
            raise CellUnavailable(f"the controller at {host} did not run ur_rtde's control script: {exc} (is it in "
                                  "remote control mode?)") from None
        try:
            ok = (self._synchronous(lambda: self.control.setTcp(list(self.arm.tcp_pose)), "setTcp")
                  and self._synchronous(lambda: self.control.setPayload(self.arm.payload_kg,
                                                                        list(self.arm.payload_cog_m)), "setPayload"))
        except CellFault as fault:
            self.close()
            raise CellUnavailable(f"the controller at {host} did not take the TCP or the payload: {fault.detail}") \
                from None
        if not ok:
            self.close()
            raise CellUnavailable(f"the controller at {host} refused the TCP or the payload")
        self.gripper.connect()

    def close(self) -> None:
        """Stop the control script and disconnect (idempotent; after :meth:`stop` on the way out). The interfaces of
        a controller that went away are let go from a thread of their own: ur_rtde keeps trying to reconnect to it,
        and its disconnect waits for that."""
        if self.control is not None:
            control, self.control = self.control, None
            if self.lost or self._silent():
                self.lost = True
                _let_go(control)
            else:
                try:
                    if control.isConnected():
                        self._synchronous(control.stopScript, "stopScript", control=control)
                    control.disconnect()
                except CellFault:
                    _let_go(control)
                except RuntimeError as exc:
                    log.warning("closing ur_rtde's control interface: %s", exc)
        if self.receive is not None:
            try:
                self.receive.disconnect()
            except RuntimeError as exc:
                log.warning("closing ur_rtde's receive interface: %s", exc)
            self.receive = None
        self.gripper.close()

    # -- the Robot protocol ---------------------------------------------------------------------------------------
    @property
    def joint_names(self) -> tuple[str, ...]:
        return ARM_JOINTS

    def joint_positions(self) -> NDArray[np.float64]:
        return np.asarray(self.receive.getActualQ(), dtype=np.float64)

    def joint_velocities(self) -> NDArray[np.float64]:
        return np.asarray(self.receive.getActualQd(), dtype=np.float64)

    def set_joint_targets(self, q_rad: NDArray[np.float64], qd_rad_s: NDArray[np.float64] | None = None) -> None:
        if self.stopped_by is not None:
            return  # stopped: the run is ending, nothing more is sent
        q = np.asarray(q_rad, dtype=np.float64).reshape(-1)
        problem = self.guard.check_target(q, self._last_target, self.joint_positions())
        if problem is not None:
            self._fault(CellFault(CellFaultKind.SAFETY_LIMIT, f"refused and not sent: {problem}"))
        changed = self._last_target is None or float(np.max(np.abs(q - self._last_target))) > 1e-7
        # a moving target (a trajectory's sample on its way) needs the tight watchdog; a hold (a target with no
        # velocity: a trajectory's last sample, a settling or cancelled executor) does not: a stall then moves nothing.
        # The same sample again (a tree re-run within a tick) changes neither.
        hold = qd_rad_s is not None and float(np.max(np.abs(qd_rad_s))) <= 1e-6
        streaming = changed and not hold
        if changed and not self.moved:
            self._first_motion()
        if streaming:
            self._target_since = time.monotonic()
            if self._watchdog_hz != WATCHDOG_MOTION_HZ:
                self._set_watchdog(WATCHDOG_MOTION_HZ)
        if not self.control.servoJ(q.tolist(), 0.0, 0.0, self.period_s, SERVO_LOOKAHEAD_S, SERVO_GAIN):
            self._check(0.0)
            self._fault(self._classified(CellFault(CellFaultKind.PROGRAM_STOPPED,
                                                   "the controller did not take a servoJ target")))
        self._wrote()
        self._servoing = True
        self._sent_since_poll = True
        self._last_target = q
        if hold and self._watchdog_hz == WATCHDOG_MOTION_HZ:
            self._set_watchdog(WATCHDOG_HOLD_HZ)

    def _first_motion(self) -> None:
        if self.confirm is not None and not self.confirm():
            self.stopped_by = CellFault(CellFaultKind.NOT_CONFIRMED, "the operator did not confirm the first motion")
            raise self.stopped_by
        self.moved = True

    def open_gripper(self) -> None:
        if self.stopped_by is None:
            self._gripper(self.gripper.open)

    def close_gripper(self, force_n: float | None = None) -> None:
        if self.stopped_by is None:
            self._gripper(lambda: self.gripper.close_on(40.0 if force_n is None else float(force_n)))

    def gripper_width_m(self) -> float:
        return self.gripper.status.width_m

    def gripper_target_width_m(self) -> float:
        return self.gripper.target_width_m

    # -- the tick loop's side -------------------------------------------------------------------------------------
    def poll(self, stalled_s: float) -> float:
        """Once a period (``CellStepper``): check the controller (a fault is raised after the arm is stopped), kick the
        watchdog, relax it once the arm holds, read the gripper. Returns the speed scaling (slider x limiter)."""
        self._watch_heartbeat(stalled_s)
        self._check(stalled_s)
        if not self._sent_since_poll:
            self.control.kickWatchdog()
            self._wrote()
        self._sent_since_poll = False
        if self._watchdog_hz == WATCHDOG_MOTION_HZ and time.monotonic() - self._target_since > HOLD_AFTER_S:
            self._set_watchdog(WATCHDOG_HOLD_HZ)  # the stream stopped without a hold: the servo holds its target
        self._gripper(self.gripper.poll)
        return float(self.receive.getSpeedScalingCombined())

    def speed_scaling(self) -> float:
        return float(self.receive.getSpeedScalingCombined())

    def tcp_wrench(self) -> NDArray[np.float64] | None:
        """The force and torque the controller measures at the TCP (base frame; None when it cannot be read)."""
        try:
            return np.asarray(self.receive.getActualTCPForce(), dtype=np.float64)
        except RuntimeError:
            return None

    def stop(self, decel_rad_s2: float = STOP_DECEL_RAD_S2) -> bool:
        """Stop the arm now (``stopJ``); True when the controller took it. Safe to call at any time; nothing is sent
        to a controller whose state stopped coming (a synchronous command would wait for it)."""
        if self.control is None or self.lost or self._silent():
            return False
        try:
            if not self.control.isConnected() or not self.control.isProgramRunning():
                return False
            if self._servoing:
                self._synchronous(lambda: self.control.servoStop(decel_rad_s2), "servoStop", STOP_TIMEOUT_S)
                self._servoing = False
            self._synchronous(lambda: self.control.stopJ(decel_rad_s2, False), "stopJ", STOP_TIMEOUT_S)
            return True
        except CellFault as fault:
            log.warning("stopJ was not answered: %s", fault.detail)
            return False

    def is_still(self, speed_rad_s: float = HOLD_SPEED_RAD_S) -> bool:
        try:
            return bool(float(np.max(np.abs(self.joint_velocities()))) < speed_rad_s)
        except RuntimeError:
            return False

    # -- inside -----------------------------------------------------------------------------------------------------
    def _state(self, script: bool = True) -> ControllerState:
        connected = bool(self.receive.isConnected()) and (not script or bool(self.control.isConnected()))
        runtime = int(self.receive.getRuntimeState()) if script else 2
        return ControllerState(connected, int(self.receive.getRobotMode()), int(self.receive.getSafetyStatusBits()),
                               runtime)

    def _watch_heartbeat(self, stalled_s: float) -> None:
        """The controller's timestamp must advance within LOST_AFTER_S while this process runs (a stall of our own
        restarts the wait: the receive thread catches up first)."""
        now = time.monotonic()
        stamp = float(self.receive.getTimestamp())
        if stamp != self._stamp or stalled_s > LOST_AFTER_S / 2:
            self._stamp, self._stamp_deadline = stamp, now + LOST_AFTER_S
        elif now > self._stamp_deadline:
            self.lost = True
            self._fault(CellFault(CellFaultKind.CONNECTION_LOST, f"no state from the controller for "
                                  f"{(now - self._stamp_deadline + LOST_AFTER_S) * 1000:.0f} ms"))

    def _silent(self, wait_s: float = 0.0) -> bool:
        """Whether the controller's state stopped coming (waiting up to ``wait_s`` for a new one)."""
        if self.receive is None:
            return True
        try:
            if not self.receive.isConnected():
                return True
            first = float(self.receive.getTimestamp())
            deadline = time.monotonic() + wait_s
            while time.monotonic() < deadline:
                if float(self.receive.getTimestamp()) != first:
                    return False
                if not self.receive.isConnected():  # ur_rtde saw the end of the connection
                    return True
                time.sleep(0.002)
            return wait_s > 0
        except RuntimeError:
            return True

    def _wrote(self) -> None:
        """The watchdog's register was written now (a servoJ, a kick, a command): a gap since the last write longer
        than the watchdog allowed is remembered (the watchdog then stopped the program)."""
        now = time.monotonic()
        gap = now - self._written_at
        if self._watchdog_hz > 0 and gap > 1.0 / self._watchdog_hz:
            self._missed = (gap, self._watchdog_hz, now)
        self._written_at = now

    def _catch_up(self) -> None:
        """After this process stalled (no write for longer than a tight watchdog allows), ur_rtde's receive thread
        first reads the state the controller sent meanwhile, oldest first: wait (a bounded while) until the state
        read is as recent as the stall is long."""
        gap = time.monotonic() - self._written_at
        if gap < 1.0 / WATCHDOG_MOTION_HZ or self._stamp < 0:
            return
        deadline = time.monotonic() + CATCH_UP_S
        while time.monotonic() < deadline:
            if float(self.receive.getTimestamp()) >= self._stamp + gap - 3 * self.period_s:
                return
            time.sleep(0.002)

    def _check(self, stalled_s: float) -> None:
        self._catch_up()
        fault = fault_from_state(self._state())
        if fault is not None:
            self._fault(self._classified(fault))

    def _classified(self, fault: CellFault) -> CellFault:
        """A stopped program after this process wrote nothing for longer than the watchdog allowed (now, or in a gap
        just before) is the watchdog's doing: the run's reason is WATCHDOG."""
        if fault.kind is not CellFaultKind.PROGRAM_STOPPED:
            return fault
        now = time.monotonic()
        gap, hz = now - self._written_at, self._watchdog_hz
        missed_gap, missed_hz, at = self._missed
        if now - at < RECENT_STALL_S and (hz <= 0 or missed_gap * missed_hz > gap * hz):
            gap, hz = missed_gap, missed_hz
        if hz > 0 and gap > 1.0 / hz:
            return CellFault(CellFaultKind.WATCHDOG, f"this process stalled for {gap:.2f} s; the controller's "
                             f"watchdog ({hz:g} Hz) stopped the program and the arm ({fault.detail})")
        return fault

    def _fault(self, fault: CellFault) -> None:
        """Stop the arm (if the controller still takes it), take no more commands, raise ``fault``."""
        if self.stopped_by is None:
            self.stopped_by = fault
            log.warning("the cell ended the run: %s", fault)
            self.stop()
        raise fault

    def _synchronous(self, call: Callable[[], RtdeObject], what: str, timeout_s: float | None = None,
                     control: RtdeObject = None) -> RtdeObject:
        """A ur_rtde call that waits for the controller's answer, bounded: it runs in a thread of its own (ur_rtde lets
        go of the interpreter while it waits), and an answer that does not come within ``timeout_s`` is a lost
        connection (a controller that went away: ur_rtde would wait, and try to reconnect, for seconds)."""
        result: list[RtdeObject] = []
        error: list[BaseException] = []

        def run() -> None:
            try:
                result.append(call())
            except BaseException as exc:  # handed to the caller's thread
                error.append(exc)

        thread = threading.Thread(target=run, name=f"ur_rtde-{what}", daemon=True)
        thread.start()
        thread.join(SYNC_TIMEOUT_S if timeout_s is None else timeout_s)
        if thread.is_alive():
            self.lost = True
            stuck = control if control is not None else self.control
            if stuck is not None:
                _LET_GO.append(stuck)  # never destroyed while ur_rtde is inside it
            raise CellFault(CellFaultKind.CONNECTION_LOST, f"the controller did not answer {what} within "
                            f"{(SYNC_TIMEOUT_S if timeout_s is None else timeout_s) * 1000:.0f} ms")
        if error:
            if isinstance(error[0], RuntimeError):
                raise CellFault(CellFaultKind.CONNECTION_LOST, f"{what} failed: {error[0]}")
            raise error[0]
        return result[0] if result else None

    def _gripper(self, call: RtdeObject) -> None:
        try:
            call()
        except CellFault as fault:
            if self._silent(LOST_AFTER_S):  # the gripper (the URCap's socket) went with the controller
                self.lost = True
                self._fault(CellFault(CellFaultKind.CONNECTION_LOST, f"the controller is gone ({fault.detail} from "
                                      f"the gripper, and no state came for {LOST_AFTER_S * 1000:.0f} ms)"))
            self._fault(fault)

    def _set_watchdog(self, hz: float) -> None:
        # a synchronous command: ur_rtde waits for the controller's answer (and tries to reconnect to a controller
        # that went away, for seconds): nothing synchronous goes to a controller whose state stopped coming
        if self.lost or self._silent():
            self.lost = True
            self._fault(CellFault(CellFaultKind.CONNECTION_LOST, "RTDE's connection to the controller is closed"))
        self._check(0.0)  # a stopped program answers no command: say why it stopped instead of waiting for it
        try:
            taken = self._synchronous(lambda: self.control.setWatchdog(hz), "setWatchdog")
        except CellFault as fault:
            self._check(0.0)  # half a second later the state is fresh: a stopped program is said as such
            self._fault(fault)
        if not taken:
            self._check(0.0)
            self._fault(self._classified(CellFault(CellFaultKind.PROGRAM_STOPPED,
                                                   "the controller did not take the watchdog")))
        self._wrote()
        self._watchdog_hz = hz


#: ur_rtde interfaces of controllers that went away, being let go (never destroyed while ur_rtde reconnects)
_LET_GO: list[RtdeObject] = []


def _let_go(interface: RtdeObject) -> None:
    """Disconnect ``interface`` in a daemon thread, waiting at most a second for it; it is kept alive either way."""
    _LET_GO.append(interface)
    thread = threading.Thread(target=interface.disconnect, name="ur_rtde-let-go", daemon=True)
    thread.start()
    thread.join(timeout=1.0)
