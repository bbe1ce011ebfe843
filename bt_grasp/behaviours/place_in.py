"""PlaceIn: set the held object down anywhere free in a tray or bin (issue 28's clear-table figure).

Where ``Place`` goes to one pose (a slot of fixed size: five household objects of 1.5 to 17 cm did not fit
the bin's six 12 cm slots), ``PlaceIn`` looks for room on the container's floor: ``bt_grasp.motion.free_area``
lists the spots where the held object (its perceived footprint grown by ``margin``) lies inside the walls and
clear of what this tree set down there before (``placed``), with the open gripper (palm and pads, where the
grasp puts them) clear of both on its way down, best packed first. Place's own checks then run on each spot in
that order, one a tick (the carry with the object held, the straight descent, the way out, the whole arm),
and the first that works is used. The container, the objects set down and the gripper are all the pipeline
knows: the scene file's installation data, the perceived detections, the robot's model.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from bt_grasp.behaviours.attempts import Exclusion
from bt_grasp.behaviours.place import _HELD_PORTS, _PlaceBase
from bt_grasp.behaviours.pose import Pose
from bt_grasp.behaviours.reasons import MOTION_REASONS, FailureReason
from bt_grasp.geometry import Mat4, inv, make_T, rot_z
from bt_grasp.motion.free_area import Floor, HeldShape, Resting, Spot, ToolPart, free_spots
from bt_grasp.motion.place_orientation import PlaceYaw, wrap_rad
from bt_grasp.scene.fixtures import Container
from bt_grasp.tree.node_api import action, inout_port, input_port

if TYPE_CHECKING:
    from bt_grasp.motion.planning_scene import Shape
    from bt_grasp.perception.results import Detection
    from bt_grasp.scene.format import Scene

#: the spots handed to Place's checks at most (each costs a plan: tens to hundreds of ms)
MAX_SPOTS = 24
#: each object's footprint is grown by this on every side unless the tree says otherwise: perception does not
#: see what lies within its height threshold (8 mm) of the table, measured up to ~8 mm beyond the footprint (the
#: wedge's thin end 7 mm, each banana tip ~7 mm, the can's body 4.5 mm round its lid)
DEFAULT_MARGIN_M = 0.01
#: and from the walls by this much unless the tree says otherwise: the unseen part and a few mm of shift in the
#: fingers (seed 9: a pen seen 130 mm long for its 146 mm, set down 1 cm from a wall, lay with a tip on it, 17 deg)
DEFAULT_WALL_MARGIN_M = 0.02
#: the open gripper stays this far from walls and objects on its way down
GRIPPER_CLEARANCE_M = 0.005
#: each earlier descent with this grip that met something before the target (the held object reaches further
#: than its perceived shape: off-centre or turned in the fingers) grows both margins by this much, up to
#: LEARNED_MARGIN_MAX_M: the next spot is one with room round it, not the next best packed (a 1 kg mug held
#: 34 mm off its perceived centre and turned 17 deg was set down on the bin's wall three times)
LEARNED_MARGIN_STEP_M = 0.03
LEARNED_MARGIN_MAX_M = 0.06

_SKIP = {"turns", "free_yaw", "turn_deg", "placed"}


def _fixture_problem(scene: Scene, name: str) -> str | None:
    fixture = scene.fixture(name)
    if fixture is None:
        known = ", ".join(f.name for f in scene.fixtures) or "none"
        return f"no fixture named '{name}' in the scene (fixtures: {known})"
    if not isinstance(fixture, Container):
        return f"'{name}' is a {fixture.kind}: PlaceIn needs a tray or a bin"
    return None


@action(
    ports=[
        input_port("fixture", str, description="the tray or bin to set the object down in", required=True),
        input_port("margin", float, DEFAULT_MARGIN_M, "each object's footprint grown by this on every side (what "
                   "perception does not see of it), m"),
        input_port("wall_margin", float, DEFAULT_WALL_MARGIN_M, "the held object's footprint this far from the walls "
                   "at least, m"),
        *[p for p in _HELD_PORTS if p.name not in _SKIP],
        inout_port("placed", object, "the objects this tree set down in trays or bins (the camera's object lists leave "
                   "them out): where the floor is taken; this one is added", default="{placed}"),
    ],
    reasons=(
        FailureReason.BAD_INPUT, FailureReason.NOT_HOLDING, FailureReason.PLACE_BLOCKED, FailureReason.DROPPED,
        FailureReason.TIMEOUT, *MOTION_REASONS,
    ),
    needs_robot=True,
)
class PlaceIn(_PlaceBase):
    """Set the held object down anywhere free in a tray or bin, clear of what was set down there before.

    FAILURE: PLACE_BLOCKED (no free spot, or none that the arm can reach and leave), NOT_HOLDING, DROPPED,
    IK_UNREACHABLE, PLAN_FAILED, TRACKING_ERROR, TIMEOUT (the fingers did not open), BAD_INPUT (a fixture
    name from the blackboard the scene lacks, or not a container).
    """

    def covers_every_turn(self) -> bool:
        return True  # the spots tried are every way the container takes the object with this grip (the best 24)

    def check_scene(self, scene: Scene) -> str | None:
        """A literal fixture the scene lacks, or that is not a container, is a load error."""
        if self.ports.key("fixture") is not None:
            return None
        problem = _fixture_problem(scene, self.ports.require("fixture", str))
        return f"PlaceIn {problem}" if problem else None

    def _container(self) -> Container | str:
        name = self.ports.require("fixture", str)
        problem = _fixture_problem(self.cell.scene, name)
        if problem is not None:
            return problem
        fixture = self.cell.scene.fixture(name)
        assert isinstance(fixture, Container)
        return fixture

    def target_pose(self) -> tuple[Pose, Detection | None] | str:
        """The container's floor centre (turned as the container): the options say where on it."""
        container = self._container()
        if isinstance(container, str):
            return container
        world = Pose(*container.center_xy_m, float(container.surface_z_m), float(container.yaw_deg), "world")
        return world.in_base(self.cell.scene.T_world_base()), None

    def orientations(self, pose: Pose, held: Detection, T_tcp_obj: Mat4, surface_z_m: float
                     ) -> list[tuple[PlaceYaw, Mat4]] | str:

        container = self._container()
        assert not isinstance(container, str)  # target_pose checked it
        T_base_box = make_T(rot_z(math.radians(pose.yaw_deg or 0.0)), [pose.x_m, pose.y_m, surface_z_m])
        floor = Floor(container.inner_size_m[0] / 2, container.inner_size_m[1] / 2,
                      container.wall_height_m - container.floor_thickness_m)
        resting = [self._resting(d, T_base_box) for d in self._placed_before()]
        shape = self._held_shape(held, T_tcp_obj)
        base_in_box = inv(T_base_box)[:2, 3]
        margin, wall_margin = self.ports.require("margin", float), self.ports.require("wall_margin", float)
        early = self.cell.attempts.early_contacts(held, T_tcp_obj)
        learned = min(LEARNED_MARGIN_MAX_M, LEARNED_MARGIN_STEP_M * len(early))
        spots: list[Spot] = []
        while not spots:
            spots = free_spots(floor, resting, shape, margin_m=margin + learned, wall_margin_m=wall_margin + learned,
                               clearance_m=GRIPPER_CLEARANCE_M,
                               far_from_xy=(float(base_in_box[0]), float(base_in_box[1])), limit=MAX_SPOTS)
            if spots or learned <= 0.0:
                break
            learned = max(0.0, round(learned - 0.01, 3))  # no room for that much: as much as there is, by cm
        if learned > 0.0:
            self._excluded.append(Exclusion(
                f"spots within {learned * 1e3:.0f} mm more of the walls and objects", early[-1].index, "room",
                f"{len(early)} descent(s) with this grip met something before the target: the held object reaches "
                "further than its perceived shape"))
        if not spots:
            length, width = (float(v) * 1e3 for v in held.size_m[:2])
            return (f"no free spot in '{container.name}' for a {length:.0f} x {width:.0f} mm object (each footprint "
                    f"grown by {margin * 1e3:.0f} mm) with the open gripper round it, beside the {len(resting)} "
                    "object(s) set down there")
        T_obj_tcp = inv(T_tcp_obj)
        z = surface_z_m + float(held.size_m[2]) / 2 + self._gap
        out = []
        for spot in spots:
            T_obj = T_base_box @ make_T(rot_z(spot.yaw_rad), [spot.x_m, spot.y_m, 0.0])
            yaw = math.atan2(T_obj[1, 0], T_obj[0, 0])
            T_place = make_T(rot_z(yaw), [T_obj[0, 3], T_obj[1, 3], z]) @ T_obj_tcp
            out.append((PlaceYaw(yaw, spot.yaw_rad, wrap_rad(yaw - float(held.yaw_rad))), T_place))
        return out

    def held_model(self, held: Detection, T_tcp_obj: Mat4, margin_m: float) -> Shape:
        """A round object (a standing can) as a cylinder: PlaceIn turns it any way, and its box turned 30 degrees
        stands 12 mm beyond its round footprint at the corners (the can's descent met the wall it was clear of)."""
        if held.shape != "round":
            return super().held_model(held, T_tcp_obj, margin_m)
        # deferred: scipy comes with it; a tree loads and validates without it
        from bt_grasp.motion.planning_scene import Cylinder

        radius = max(float(held.size_m[0]), float(held.size_m[1])) / 2 + margin_m / 2
        return Cylinder.at("held", radius, float(held.size_m[2]) + margin_m, T_tcp_obj)

    @staticmethod
    def _resting(placed: Detection, T_base_box: Mat4) -> Resting:
        """An object set down before, in the container's frame (its perceived footprint and height)."""
        local = inv(T_base_box) @ np.array([*placed.centroid_base_m[:2], 0.0, 1.0])
        yaw = float(placed.yaw_rad) - math.atan2(T_base_box[1, 0], T_base_box[0, 0])
        return Resting((float(local[0]), float(local[1])), yaw, (float(placed.size_m[0]), float(placed.size_m[1])),
                       float(placed.size_m[2]))

    def _held_shape(self, held: Detection, T_tcp_obj: Mat4) -> HeldShape:
        """The held object's footprint and the open gripper's boxes in its resting frame (the middle of its
        footprint on the surface, x along its length): where the grasp puts them."""
        # deferred: pinocchio and coal come with it; a tree loads and validates without them
        from bt_grasp.motion.gripper_shape import gripper_boxes

        length, width, height = (float(v) for v in held.size_m)
        T_rest_tcp = make_T(np.eye(3), [0.0, 0.0, height / 2]) @ inv(T_tcp_obj)
        boxes = gripper_boxes(float(self.cell.kinematics.opening_m), self.cell.kinematics.urdf_path)
        parts = tuple(ToolPart(b.size_m, T_rest_tcp @ b.T_tcp_box) for b in boxes)
        return HeldShape(length, width, height, held.shape == "round", parts)
