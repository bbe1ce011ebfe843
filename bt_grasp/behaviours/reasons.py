"""Why a leaf failed: names a tree can test with ``FailureIs reason="..."``.

The built-in set lives in :mod:`bt_grasp.tree.reasons` (the tree's ``FailureIs`` checks names against it plus
the reasons plugins register); it is re-exported here for the robot leaves.
"""

from __future__ import annotations

from bt_grasp.tree.reasons import FailureReason, Reason, ReasonLike, reason_name

__all__ = ["FailureReason", "Reason", "ReasonLike", "reason_name"]
