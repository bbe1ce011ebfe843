"""Why a leaf failed: names a tree can test with ``FailureIs reason="..."``.

The built-in set lives in :mod:`bt_grasp.tree.reasons` (the tree's ``FailureIs`` checks names against it plus
the reasons plugins register); it is re-exported here for the robot leaves, with the groups of reasons a
planned motion and a perception step may end in (the leaves that run them declare them).
"""

from __future__ import annotations

from bt_grasp.tree.reasons import FailureReason, Reason, ReasonLike, reason_name

R = FailureReason

#: what a planned, executed motion may fail with (bt_grasp.behaviours.motion_job)
MOTION_REASONS: tuple[FailureReason, ...] = (R.IK_UNREACHABLE, R.COLLISION, R.PLAN_FAILED, R.TRACKING_ERROR)
#: what one capture and detection may fail with (bt_grasp.behaviours.perceive.perceive_once)
PERCEPTION_REASONS: tuple[FailureReason, ...] = (R.CALIBRATION_MISSING, R.NO_FRAME, R.BAD_INPUT, R.NO_DETECTION)

__all__ = ["MOTION_REASONS", "PERCEPTION_REASONS", "FailureReason", "Reason", "ReasonLike", "reason_name"]
