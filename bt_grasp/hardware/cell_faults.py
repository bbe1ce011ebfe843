"""What can stop a real cell's run from outside the tree, as typed reasons: every state the controller reports that
ends a run (read from RTDE each control period), a lost connection, a stalled process, a silent gripper.

A :class:`CellFault` is raised by the cell's devices (``bt_grasp.hardware.ur_arm``, ``robotiq_client``) from the tick
loop; the run (``bt_grasp.episode.cell_run``) stops the arm, ends with the fault's kind as its reason and finishes
its log. :func:`fault_from_state` is the one place RTDE's numbers become a kind (UR's RTDE guide, the
``robot_mode``, ``safety_status_bits`` and ``runtime_state`` outputs).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from bt_grasp.errors import BtGraspError


class CellFaultKind(enum.StrEnum):
    """Why a real cell's run was ended by the cell (the run's ``reason``)."""

    PROTECTIVE_STOP = "PROTECTIVE_STOP"  # the safety system stopped the arm (a collision, a limit, a request)
    SAFEGUARD_STOP = "SAFEGUARD_STOP"  # a safeguard input (a light curtain, a door) stopped the arm
    EMERGENCY_STOP = "EMERGENCY_STOP"  # an emergency stop button (the pendant's, the system's, the robot's)
    SAFETY_FAULT = "SAFETY_FAULT"  # the safety system reports a violation or a fault
    ROBOT_NOT_RUNNING = "ROBOT_NOT_RUNNING"  # the arm is not powered with its brakes released
    PROGRAM_STOPPED = "PROGRAM_STOPPED"  # the control program stopped (from the pendant, or the controller)
    CONNECTION_LOST = "CONNECTION_LOST"  # RTDE to the controller is gone
    WATCHDOG = "WATCHDOG"  # this process stalled; the controller's watchdog stopped the arm
    GRIPPER_NOT_ANSWERING = "GRIPPER_NOT_ANSWERING"  # the gripper's socket did not answer within its timeout
    GRIPPER_FAULT = "GRIPPER_FAULT"  # the gripper reports a fault
    SAFETY_LIMIT = "SAFETY_LIMIT"  # a streamed target failed the cell's checks: refused, nothing sent
    NOT_CONFIRMED = "NOT_CONFIRMED"  # the operator did not confirm the arm's first motion: nothing moved


DESCRIPTIONS: dict[CellFaultKind, str] = {
    CellFaultKind.PROTECTIVE_STOP: "the robot's safety system stopped the arm (protective stop)",
    CellFaultKind.SAFEGUARD_STOP: "a safeguard input stopped the arm",
    CellFaultKind.EMERGENCY_STOP: "an emergency stop was pressed",
    CellFaultKind.SAFETY_FAULT: "the robot's safety system reports a violation or a fault",
    CellFaultKind.ROBOT_NOT_RUNNING: "the arm is not powered on with its brakes released",
    CellFaultKind.PROGRAM_STOPPED: "the control program was stopped (from the pendant, or by the controller)",
    CellFaultKind.CONNECTION_LOST: "the connection to the controller was lost",
    CellFaultKind.WATCHDOG: "this process stalled and the controller's watchdog stopped the arm",
    CellFaultKind.GRIPPER_NOT_ANSWERING: "the gripper did not answer",
    CellFaultKind.GRIPPER_FAULT: "the gripper reports a fault",
    CellFaultKind.SAFETY_LIMIT: "a motion target failed the cell's checks and was not sent",
    CellFaultKind.NOT_CONFIRMED: "the operator did not confirm the arm's first motion; nothing moved",
}


class CellFault(BtGraspError):
    """The cell ended the run: ``kind`` (the run's reason) and one sentence of detail."""

    def __init__(self, kind: CellFaultKind, detail: str) -> None:
        self.kind = kind
        self.detail = detail
        super().__init__(f"{kind.value}: {detail}")


class CellUnavailable(BtGraspError):
    """The cell cannot be used before anything moves (not reachable, not ready): one sentence, exit code 2."""

    exit_code = 2


#: RTDE ``robot_mode`` RUNNING (powered, brakes released); ``runtime_state`` PLAYING
ROBOT_MODE_RUNNING = 7
RUNTIME_PLAYING = 2
_ROBOT_MODES = {-1: "no controller", 0: "disconnected", 1: "confirming safety", 2: "booting", 3: "powered off",
                4: "powered on", 5: "idle (brakes on)", 6: "in backdrive", 7: "running", 8: "updating firmware"}
_RUNTIME = {0: "stopping", 1: "stopped", 2: "playing", 3: "pausing", 4: "paused", 5: "resuming"}


@dataclass(frozen=True)
class ControllerState:
    """What the tick loop reads of the controller each period (RTDE outputs)."""

    connected: bool
    robot_mode: int
    safety_status_bits: int
    runtime_state: int


def fault_from_state(state: ControllerState) -> CellFault | None:
    """The fault ``state`` shows, most severe first, or None when the arm may move (UR's RTDE guide:
    ``safety_status_bits`` bit 2 protective stop, 4 safeguard stop, 5-7 emergency stops, 8 violation, 9 fault)."""
    if not state.connected:
        return CellFault(CellFaultKind.CONNECTION_LOST, "RTDE's connection to the controller is closed")
    bits = state.safety_status_bits
    if bits & ((1 << 5) | (1 << 6) | (1 << 7)):
        which = [name for bit, name in ((5, "system"), (6, "robot"), (7, "emergency")) if bits & (1 << bit)]
        return CellFault(CellFaultKind.EMERGENCY_STOP, f"{'/'.join(which)} emergency stop "
                                                       f"(safety_status_bits {bits:#x})")
    if bits & (1 << 8) or bits & (1 << 9):
        return CellFault(CellFaultKind.SAFETY_FAULT, f"the safety system reports a "
                                                     f"{'violation' if bits & (1 << 8) else 'fault'} "
                                                     f"(safety_status_bits {bits:#x})")
    if bits & (1 << 2):
        return CellFault(CellFaultKind.PROTECTIVE_STOP, f"protective stop (safety_status_bits {bits:#x})")
    if bits & (1 << 4):
        return CellFault(CellFaultKind.SAFEGUARD_STOP, f"safeguard stop (safety_status_bits {bits:#x})")
    if state.robot_mode != ROBOT_MODE_RUNNING:
        mode = _ROBOT_MODES.get(state.robot_mode, f"mode {state.robot_mode}")
        return CellFault(CellFaultKind.ROBOT_NOT_RUNNING, f"the robot is {mode}")
    if state.runtime_state != RUNTIME_PLAYING:
        runtime = _RUNTIME.get(state.runtime_state, f"state {state.runtime_state}")
        return CellFault(CellFaultKind.PROGRAM_STOPPED, f"the control program is {runtime}")
    return None
