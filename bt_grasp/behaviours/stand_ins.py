"""What the robot leaves promise, for their dry-run stand-ins (``bt-grasp tree run --dry``).

:data:`FAILURE_REASONS` lists, per leaf type, the reasons the real leaf may fail with (its own ``failed``
calls plus those of the motion or perception job it runs): ``--outcome NAME=failure:REASON`` must name
one, and ``--random SEED`` draws among them. :class:`RobotStandIns` gives the value a stand-in writes to
each output port: a list of perceived objects (red, green and blue boxes) where the real leaf writes
detections, a pose where it writes a pose, a width in metres for ``Grasp``; values only other robot leaves
read (a grasp plan, a calibration, a track) are a :class:`bt_grasp.tree.dry_run.StandInValue`.
"""

from __future__ import annotations

from bt_grasp.behaviours.reasons import FailureReason as R
from bt_grasp.perception.results import Detection
from bt_grasp.pose import Pose
from bt_grasp.tree.dry_run import type_placeholder
from bt_grasp.tree.registry import NodeSpec, PortSpec

_MOTION = (R.IK_UNREACHABLE, R.COLLISION, R.PLAN_FAILED, R.TRACKING_ERROR)  # a planned, executed motion
_PERCEPTION = (R.CALIBRATION_MISSING, R.NO_FRAME, R.BAD_INPUT, R.NO_DETECTION)  # one capture + detection

#: per leaf type, the reasons the real leaf may fail with
FAILURE_REASONS: dict[str, tuple[R, ...]] = {
    "LoadCalibration": (R.CALIBRATION_MISSING,),
    "Calibrate": (R.CALIBRATION_FAILED, R.PLAN_FAILED, R.TRACKING_ERROR),
    "Perceive": _PERCEPTION,
    "ObjectVisible": _PERCEPTION,
    "PerceiveAll": _PERCEPTION,
    "PlanGrasp": (R.NO_DETECTION, R.NOTHING_TO_GRASP, R.IK_UNREACHABLE, R.PLAN_FAILED),
    "Approach": (R.BAD_INPUT, *_MOTION),
    "Lift": (R.BAD_INPUT, R.SLIPPED, *_MOTION),
    "Retreat": _MOTION,
    "MoveHome": _MOTION,
    "MoveAbove": _MOTION,
    "MoveTo": (R.BAD_INPUT, *_MOTION),
    "LookAt": (R.BAD_INPUT, R.CALIBRATION_MISSING, *_MOTION),
    "OpenGripper": (R.TIMEOUT,),
    "Grasp": (R.GRASP_EMPTY, R.TIMEOUT),
    "IsGrasped": (R.GRASP_EMPTY, R.SLIPPED),
    "FixturePose": (R.BAD_INPUT,),
    "Place": (R.BAD_INPUT, R.NOT_HOLDING, R.PLACE_BLOCKED, R.DROPPED, R.TIMEOUT, *_MOTION),
    "PlaceOn": (R.BAD_INPUT, R.NOT_HOLDING, R.PLACE_BLOCKED, R.DROPPED, R.TIMEOUT, *_MOTION),
    "FollowTarget": (R.BAD_INPUT, R.TARGET_LOST, R.IK_UNREACHABLE),
    "SelectObject": (R.BAD_INPUT, R.NO_DETECTION),
    "ObjectPose": (R.BAD_INPUT,),
    "ObjectInfo": (R.BAD_INPUT,),
    "ObjectCount": (R.BAD_INPUT, R.NO_DETECTION, R.COUNT_EXCEEDED),
}


def _box(label: str, x: float, y: float) -> Detection:
    size = 0.05
    corners = tuple((x + dx * size / 2, y + dy * size / 2) for dx, dy in ((-1, -1), (1, -1), (1, 1), (-1, 1)))
    return Detection(
        label, (0, 0, 1, 1), (x, y, size / 2), (size, size, size), 0.0, 1000, 1.0, 1.0,
        ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)), corners,
    )  # fmt: skip


#: the objects a stand-in "sees": a red, a green and a blue 5 cm box on the table, in the base frame
SEEN = (_box("red", 0.45, 0.10), _box("green", 0.45, 0.0), _box("blue", 0.45, -0.10))


class RobotStandIns:
    """The :class:`bt_grasp.tree.dry_run.StandInCatalog` of bt_grasp's robot leaves."""

    def failure_reasons(self, spec: NodeSpec) -> tuple[str, ...]:
        return tuple(r.value for r in FAILURE_REASONS.get(spec.name, ()))

    def placeholder(self, spec: NodeSpec, port: PortSpec) -> object:
        if port.name == "objects":
            return SEEN
        if port.name in ("target", "object"):
            return SEEN[0]
        if port.name == "pose":
            return Pose(0.45, -0.25, 0.0, 0.0)
        if spec.name == "Grasp" and port.name == "width":
            return 0.05
        return type_placeholder(port, spec.name)
