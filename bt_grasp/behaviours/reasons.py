"""Why a leaf failed: names a tree can test with ``FailureIs reason="..."``."""

from __future__ import annotations

import enum


class FailureReason(enum.StrEnum):
    NO_FRAME = "NO_FRAME"  # the camera returned no frame
    NO_DETECTION = "NO_DETECTION"  # nothing (matching) stands on the table
    NOTHING_TO_GRASP = "NOTHING_TO_GRASP"  # objects seen, none graspable (too wide, no clearance)
    IK_UNREACHABLE = "IK_UNREACHABLE"
    PLAN_FAILED = "PLAN_FAILED"
    COLLISION = "COLLISION"  # the start or goal collides with the planning scene
    TRACKING_ERROR = "TRACKING_ERROR"  # the arm did not follow its trajectory (stall, contact)
    GRASP_EMPTY = "GRASP_EMPTY"  # the fingers closed on nothing
    SLIPPED = "SLIPPED"  # the object left the fingers during the lift
    TIMEOUT = "TIMEOUT"
    CALIBRATION_MISSING = "CALIBRATION_MISSING"
    CALIBRATION_FAILED = "CALIBRATION_FAILED"
    TARGET_LOST = "TARGET_LOST"  # a followed target left the camera's view
    BAD_INPUT = "BAD_INPUT"  # a port held something of the wrong kind
    NOT_HOLDING = "NOT_HOLDING"  # Place/PlaceOn started with nothing between the fingers
    DROPPED = "DROPPED"  # the held object left the fingers while it was carried
    PLACE_BLOCKED = "PLACE_BLOCKED"  # the place target is occupied, or the descent met something early
    COUNT_EXCEEDED = "COUNT_EXCEEDED"  # ObjectCount: more objects than the port ``max`` allows
