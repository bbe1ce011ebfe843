"""Every controller state that ends a run is one typed reason (UR's RTDE guide's robot_mode, safety_status_bits and
runtime_state), the most severe first."""

from __future__ import annotations

import pytest

from bt_grasp.hardware.cell_faults import CellFaultKind, ControllerState, fault_from_state

RUNNING, PLAYING, NORMAL = 7, 2, 1


@pytest.mark.parametrize(("state", "kind"), [
    (ControllerState(True, RUNNING, NORMAL, PLAYING), None),
    (ControllerState(False, RUNNING, NORMAL, PLAYING), CellFaultKind.CONNECTION_LOST),
    (ControllerState(True, RUNNING, NORMAL | 1 << 2 | 1 << 10, 4), CellFaultKind.PROTECTIVE_STOP),
    (ControllerState(True, RUNNING, NORMAL | 1 << 4, 4), CellFaultKind.SAFEGUARD_STOP),
    (ControllerState(True, RUNNING, 1 << 7 | 1 << 2, 4), CellFaultKind.EMERGENCY_STOP),  # severest first
    (ControllerState(True, RUNNING, 1 << 6, 1), CellFaultKind.EMERGENCY_STOP),
    (ControllerState(True, RUNNING, 1 << 9, 1), CellFaultKind.SAFETY_FAULT),
    (ControllerState(True, 3, NORMAL, 1), CellFaultKind.ROBOT_NOT_RUNNING),  # powered off
    (ControllerState(True, RUNNING, NORMAL, 1), CellFaultKind.PROGRAM_STOPPED),  # stopped from the pendant
    (ControllerState(True, RUNNING, NORMAL, 4), CellFaultKind.PROGRAM_STOPPED),  # paused
])
def test_controller_states_map_to_one_reason(state: ControllerState, kind: CellFaultKind | None) -> None:
    fault = fault_from_state(state)
    assert (fault.kind if fault is not None else None) is kind
    if fault is not None:
        assert str(fault).startswith(kind.value + ": ") and "\n" not in str(fault)  # type: ignore[union-attr]
