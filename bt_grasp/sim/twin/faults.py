"""The faults a twin produces on demand (a table of kinds: what each does and what a client sees)."""

from __future__ import annotations

import enum


class TwinFault(enum.StrEnum):
    PROTECTIVE_STOP = "protective-stop"
    PENDANT_STOP = "pendant-stop"
    DROP_CONNECTIONS = "drop-connections"
    GRIPPER_SILENT = "gripper-silent"
    GRIPPER_ANSWERS = "gripper-answers"


#: what each fault does, and how a client observes it (docs/twin.md shows this table)
FAULTS: dict[TwinFault, tuple[str, str]] = {
    TwinFault.PROTECTIVE_STOP: (
        "a protective stop, as if the safety system tripped (a collision the physics sees does the same)",
        "safety_mode 3 (PROTECTIVE_STOP), safety_status_bits bit 2, runtime_state 4 (PAUSED); the arm halts",
    ),
    TwinFault.PENDANT_STOP: (
        "the program is stopped from the teach pendant",
        "runtime_state 1 (STOPPED), robot_status_bits bit 1 cleared; the arm halts; the control script is gone",
    ),
    TwinFault.DROP_CONNECTIONS: (
        "every connection is cut, and new ones are closed at once for SECONDS (default 1)",
        "the client's socket sees end-of-file; the program keeps running (its watchdog, if set, stops it)",
    ),
    TwinFault.GRIPPER_SILENT: (
        "the gripper stops answering: its socket stays open and reads requests, and answers nothing",
        "a gripper client's read times out; RTDE shows nothing (as on a robot)",
    ),
    TwinFault.GRIPPER_ANSWERS: ("the gripper answers again", "replies resume"),
}
