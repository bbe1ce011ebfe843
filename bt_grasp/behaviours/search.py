"""FindLost and AttemptRules: the run's memory of its attempts (``bt_grasp.behaviours.attempts``) as tree nodes.

``FindLost`` looks for the object a failed grasp was on, in a fresh object list: a grasp that closes on
nothing, slips or stalls may push the object (a lying bottle or can rolls away), and the attribute the tree
chose it by (a class the learned detector no longer names from its new side, a colour half hidden) may no
longer match. It is found by what was seen of it at the attempt: the size of its box, its colour, its class
when named, nearest where it was. ``AttemptRules`` sets when two attempts count as the same (issue 46's numbers
are the defaults).
"""

from __future__ import annotations

import math

from bt_grasp.behaviours.attempts import AttemptRules as Rules
from bt_grasp.behaviours.attempts import ObjectSeen
from bt_grasp.behaviours.base import RobotLeaf
from bt_grasp.behaviours.objects import class_of, object_list
from bt_grasp.behaviours.reasons import FailureReason
from bt_grasp.perception.results import Detection
from bt_grasp.tree.node_api import Status, action, input_port, output_port

#: the lost object's box and a candidate's may differ by this share of each side (seen from another side)
SIZE_SHARE = 0.4
#: ... and it is looked for this far from where it was at most, m (a rolling can or bottle)
SEARCH_RADIUS_M = 0.45


def _sides(size: tuple[float, float, float] | tuple[float, ...]) -> list[float]:
    return sorted(float(v) for v in size)


def lost_match(lost: ObjectSeen, det: Detection) -> float | None:
    """How well ``det`` stands for the lost object (lower is better), or None when it cannot be it: another
    class named, a colour that is not its own, a box of other sides (sorted, each within :data:`SIZE_SHARE`), or
    farther than :data:`SEARCH_RADIUS_M` from where it was."""
    named = class_of(det)
    if lost.class_name and named and named != lost.class_name:
        return None
    colour = str(getattr(det, "color_name", "") or "")
    if lost.color_name and colour and colour != lost.color_name:
        return None
    a, b = _sides(lost.size_m), _sides(det.size_m)
    if any(abs(x - y) > SIZE_SHARE * max(x, y, 1e-6) for x, y in zip(a, b, strict=True)):
        return None
    distance = math.dist(lost.centroid_m[:2], det.centroid_base_m[:2])
    if distance > SEARCH_RADIUS_M:
        return None
    return distance + sum(abs(x - y) for x, y in zip(a, b, strict=True))


@action(
    ports=[
        input_port("objects", object, "{objects}", "a fresh object list (from PerceiveAll)"),
        output_port("object", object, "the object the last failed grasp was on, where it is now", default="{target}"),
    ],
    reasons=(FailureReason.NO_DETECTION, FailureReason.BAD_INPUT),
    needs_robot=True,
)
class FindLost(RobotLeaf):
    """Find the object the last failed grasp was on in a fresh object list (it may have rolled away, and no
    longer answer to its class or colour): by its box's sides, its colour and class when seen, nearest where it
    was. FAILURE: NO_DETECTION (no failed grasp to look for, or nothing like it in the list), BAD_INPUT."""

    def update(self) -> Status:
        objects = object_list(self.ports.get("objects"))
        if objects is None:
            return self.fail(FailureReason.BAD_INPUT, "'objects' is not an object list: run PerceiveAll first")
        attempt = self.cell.attempts.last_lost()
        if attempt is None:
            return self.fail(FailureReason.NO_DETECTION, "no failed grasp to look for: nothing was lost")
        lost = attempt.object
        scored = [(score, i) for i, d in enumerate(objects) if (score := lost_match(lost, d)) is not None]
        if not scored:
            return self.fail(FailureReason.NO_DETECTION, f"the {lost.describe()} of attempt #{attempt.index} is "
                             f"not among the {len(objects)} object(s) seen")
        found = objects[min(scored)[1]]
        self.cell.attempts.moved(lost, found)  # what was tried on it goes with it
        self.ports.set("object", found)
        moved = math.dist(lost.centroid_m[:2], found.centroid_base_m[:2])
        self.feedback_message = (f"the {lost.describe()} of attempt #{attempt.index}: {moved * 100:.0f} cm from "
                                 f"where it was, {class_of(found) or 'unnamed'}")
        return Status.SUCCESS


@action(
    ports=[
        input_port("same_mm", float, Rules.same_m * 1e3, "two attempts on one object and of one family are the same "
                   "when their tool poses lie this close, mm ..."),
        input_port("same_deg", float, Rules.same_deg, "... and within this angle, degrees"),
        input_port("stall_mm", float, Rules.stall_m * 1e3, "a grasp that stalled in contact rules out grasps this "
                   "close, mm ..."),
        input_port("stall_deg", float, Rules.stall_deg, "... and within this angle, degrees"),
    ],
    reasons=(FailureReason.BAD_INPUT,),
    needs_robot=True,
)
class AttemptRules(RobotLeaf):
    """Set when two attempts are the same, and how far a stall reaches, for the rest of the run (the run's memory
    of its attempts, ``bt_grasp.behaviours.attempts``). FAILURE: BAD_INPUT (a negative or non-finite number)."""

    def update(self) -> Status:
        try:
            rules = Rules(same_m=self.ports.require("same_mm", float) / 1e3,
                          same_deg=self.ports.require("same_deg", float),
                          stall_m=self.ports.require("stall_mm", float) / 1e3,
                          stall_deg=self.ports.require("stall_deg", float))
        except ValueError as exc:
            return self.fail(FailureReason.BAD_INPUT, str(exc))
        self.cell.attempts.rules = rules
        self.feedback_message = (f"same: {rules.same_m * 1e3:.0f} mm, {rules.same_deg:.0f} deg; stall: "
                                 f"{rules.stall_m * 1e3:.0f} mm, {rules.stall_deg:.0f} deg")
        return Status.SUCCESS
