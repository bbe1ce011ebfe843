"""What the robot leaves promise, for their dry-run stand-ins (``bt-grasp tree run --dry``).

The reasons a stand-in fails with are the leaf's own declaration (``NodeSpec.failure_reasons``; the robot
leaves' are declared in :mod:`bt_grasp.behaviours.library`): ``--outcome NAME=failure:REASON`` must name one, and
``--random SEED`` draws among them. :class:`RobotStandIns` gives the value a stand-in writes to
each output port: a list of perceived objects (red, green and blue boxes) where the real leaf writes
detections, a pose where it writes a pose, a width in metres for ``Grasp``; values only other robot leaves
read (a grasp plan, a calibration, a track) are a :class:`bt_grasp.tree.stand_in.StandInValue`. Given the run's
scene (``tree run --dry --scene``), ``FixturePose`` writes the pose the real leaf computes from that scene, and fails
with BAD_INPUT where the real one would (a fixture or slot the scene lacks).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bt_grasp.behaviours.objects import fixture_pose
from bt_grasp.behaviours.pose import Pose
from bt_grasp.behaviours.reasons import FailureReason
from bt_grasp.perception.results import Detection
from bt_grasp.tree.registry import PortSpec
from bt_grasp.tree.stand_in import StandIn, StandInRefusal, type_placeholder

if TYPE_CHECKING:
    from bt_grasp.scene.format import Scene


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
    """The :class:`bt_grasp.tree.stand_in.StandInCatalog` of bt_grasp's robot leaves; ``scene``: the run's scene,
    where fixtures are."""

    def __init__(self, scene: Scene | None = None) -> None:
        self.scene = scene

    def placeholder(self, node: StandIn, port: PortSpec) -> object:
        spec = node.original
        if spec.name == "FixturePose" and port.name == "pose" and self.scene is not None:
            pose = fixture_pose(self.scene, node.ports.require("fixture", str), node.ports.require("slot", int),
                                node.ports.require("slot_size", float))
            if isinstance(pose, str):
                raise StandInRefusal(FailureReason.BAD_INPUT.value, pose)
            return pose
        if port.name == "objects":
            return SEEN
        if port.name in ("target", "object"):
            return SEEN[0]
        if port.name == "pose":
            return Pose(0.45, -0.25, 0.0, 0.0)
        if spec.name == "Grasp" and port.name == "width":
            return 0.05
        return type_placeholder(port, spec.name)
