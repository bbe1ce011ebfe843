"""Why a leaf failed: the built-in reasons plus the ones a registry's plugins declare.

A reason is a small value (:class:`Reason`): an upper-case name such as ``NO_DETECTION`` and one sentence
saying what it means. The built-in ones are :class:`FailureReason` (a StrEnum, so robot leaves keep typed
names); a plugin declares its own with ``registry.register_reason(Reason("BARCODE_UNREADABLE", "..."))``.
A tree's ``FailureIs reason="..."`` must name a reason its registry knows (a load error naming file:line
otherwise); recordings and replay carry the name as text, so registered reasons go everywhere built-in
ones go.
"""

from __future__ import annotations

import enum
import re
from dataclasses import dataclass

from bt_grasp.tree.exceptions import DeclarationError

_NAME = re.compile(r"[A-Z][A-Z0-9_]{0,63}")

#: root blackboard keys :meth:`bt_grasp.tree.leaf_node.Leaf.fail` writes (read by the ``FailureIs`` condition;
#: both are removed when the whole tree succeeds)
FAILURE_REASON_KEY = "failure_reason"
FAILED_LEAF_KEY = "failed_leaf"


class FailureReason(enum.StrEnum):
    """The built-in reasons of bt_grasp's robot leaves."""

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
    SAFETY_LIMIT = "SAFETY_LIMIT"  # a real cell refused a motion before sending it (workspace box, table, caps)
    INTERCEPT_MISSED = "INTERCEPT_MISSED"  # the object on the belt will have left the reach before the grasp is over


@dataclass(frozen=True)
class Reason:
    """A failure reason a leaf may report and ``FailureIs`` may test.

    Attributes:
        name: upper-case letters, digits and underscores, starting with a letter (``BARCODE_UNREADABLE``)
        description: one sentence: what happened when a leaf fails with it
    """

    name: str
    description: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not _NAME.fullmatch(self.name):
            raise DeclarationError(
                f"failure reason {self.name!r} must be upper-case letters, digits and underscores, "
                "starting with a letter (at most 64 characters)"
            )

    def __str__(self) -> str:
        return self.name


#: what :meth:`bt_grasp.tree.leaf_node.Leaf.fail` accepts: a built-in reason, a declared one, or its name
ReasonLike = FailureReason | Reason | str


def reason_name(reason: ReasonLike) -> str:
    """The name a reason is recorded and matched by."""
    if isinstance(reason, Reason):
        return reason.name
    return str(reason.value) if isinstance(reason, FailureReason) else str(reason)


_DESCRIPTIONS: dict[FailureReason, str] = {
    FailureReason.NO_FRAME: "The camera returned no frame.",
    FailureReason.NO_DETECTION: "Nothing (matching) stands on the table.",
    FailureReason.NOTHING_TO_GRASP: "Objects were seen, none is graspable (too wide, no clearance).",
    FailureReason.IK_UNREACHABLE: "No arm configuration reaches the pose.",
    FailureReason.PLAN_FAILED: "The motion planner found no collision-free path.",
    FailureReason.COLLISION: "The start or goal collides with the planning scene.",
    FailureReason.TRACKING_ERROR: "The arm did not follow its trajectory (stall, contact).",
    FailureReason.GRASP_EMPTY: "The fingers closed on nothing.",
    FailureReason.SLIPPED: "The object left the fingers during the lift.",
    FailureReason.TIMEOUT: "The leaf ran out of simulated time.",
    FailureReason.CALIBRATION_MISSING: "No camera calibration was loaded.",
    FailureReason.CALIBRATION_FAILED: "The camera calibration could not be computed.",
    FailureReason.TARGET_LOST: "A followed target left the camera's view.",
    FailureReason.BAD_INPUT: "A port held something of the wrong kind.",
    FailureReason.NOT_HOLDING: "Place/PlaceOn started with nothing between the fingers.",
    FailureReason.DROPPED: "The held object left the fingers while it was carried.",
    FailureReason.PLACE_BLOCKED: "The place target is occupied, or the descent met something early.",
    FailureReason.COUNT_EXCEEDED: "ObjectCount saw more objects than its port max allows.",
    FailureReason.SAFETY_LIMIT: "A real cell refused a motion before sending it (workspace box, table, caps).",
    FailureReason.INTERCEPT_MISSED: "The object on the belt can no longer be intercepted: it will have left the "
                                    "arm's reach before the grasp would be over.",
}


def builtin_reasons() -> tuple[Reason, ...]:
    """The built-in reasons as values (what every registry from ``builtin_registry()`` starts with)."""
    return tuple(Reason(r.value, _DESCRIPTIONS.get(r, "")) for r in FailureReason)
