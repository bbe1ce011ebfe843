"""Regrasp to place (issue 46): when no placement is reachable with the grip held, set the object down in free
space, grasp it again with a grip that makes the placement reachable, and place it.

Three leaves, which ``trees/lib/place.xml``'s ``RegraspToPlace`` puts together after the placement's own
retries:

- ``GripBlocksPlace`` (condition): SUCCESS when the last placement found every orientation the held object's
  footprint allows blocked with the grip held (now, or before: each one repeated a failed attempt), from the
  run's memory of its attempts (``bt_grasp.behaviours.attempts``);
- ``SetDown``: Place's checks on spots of the table, clear of every object seen by ``clearance`` (room for any
  grasp of the next attempt), nearest the tool first; writes where the object came to rest;
- ``PlanRegrasp``: PlanGrasp keeping only a grasp whose grip lets the object be set down at ``place_pose``:
  some orientation its footprint allows has a release pose with an arm configuration clear of the scene
  seen (the object held, as carried) and a pre-place pose straight above it, not ruled out by an earlier
  attempt. Planned, not tried blindly.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bt_grasp.behaviours.attempts import ObjectSeen
from bt_grasp.behaviours.base import RobotLeaf
from bt_grasp.behaviours.grasp_plan import GraspPlan
from bt_grasp.behaviours.motion_job import PathFailure
from bt_grasp.behaviours.motion_leaves import PLAN_GRASP_PORTS, PLAN_GRASP_REASONS, PlanGrasp, detection_box
from bt_grasp.behaviours.objects import object_list
from bt_grasp.behaviours.place import (
    _HELD_PORTS,
    RELEASE_IK_SEEDS,
    RELEASE_IK_SOLUTIONS,
    _PlaceBase,
    held_offset,
    place_options,
    same_object,
    table_z_base,
)
from bt_grasp.behaviours.pose import Pose
from bt_grasp.behaviours.reasons import MOTION_REASONS, FailureReason
from bt_grasp.geometry import Mat4, inv
from bt_grasp.motion.place_orientation import PlaceYaw
from bt_grasp.robot_description import TCP_LINK
from bt_grasp.tree.node_api import Status, action, condition, input_port, output_port

if TYPE_CHECKING:
    from bt_grasp.motion.planning_scene import PlanningScene
    from bt_grasp.perception.results import Detection, GraspCandidate

#: free room round an object set down for a regrasp, m: the open gripper's pads and palm from any side
SET_DOWN_CLEARANCE_M = 0.06
#: the grid of table spots SetDown considers, m apart
SET_DOWN_STEP_M = 0.02
#: the spots handed to Place's checks at most (each costs a plan)
SET_DOWN_SPOTS = 12
#: the release gap PlanRegrasp checks a place with (Place's default)
RELEASE_GAP_M = 0.003
#: ... and the pre-place pose's height above the release (Place's default ``approach``)
APPROACH_M = 0.10


@condition(reasons=(FailureReason.PLACE_BLOCKED,), needs_robot=True)
class GripBlocksPlace(RobotLeaf):
    """SUCCESS when the last placement found every orientation the held object's footprint allows blocked with
    the grip held (now, or before: each repeated a failed attempt); FAILURE otherwise, with no reason (a question;
    the reason it declares is the one it is asked after, what a dry run's stand-in answers with)."""

    def update(self) -> Status:
        if self.cell.attempts.grip_blocked:
            self.feedback_message = "no orientation works with the grip held: regrasp"
            return Status.SUCCESS
        self.feedback_message = "the last placement was not blocked for every orientation"
        return Status.FAILURE


def _raised(T: Mat4, dz: float) -> Mat4:
    out = np.array(T, dtype=float)
    out[2, 3] += dz
    return out


@action(
    ports=[
        input_port("clearance", float, SET_DOWN_CLEARANCE_M, "free room kept round the object set down (for any grasp "
                   "of the next attempt), m"),
        output_port("pose", object, "where the object came to rest (base frame, its yaw)", default="{set_down_pose}"),
        *[p for p in _HELD_PORTS if p.name not in ("turns", "free_yaw", "turn_deg", "placed")],
    ],
    reasons=(
        FailureReason.BAD_INPUT, FailureReason.NOT_HOLDING, FailureReason.PLACE_BLOCKED, FailureReason.DROPPED,
        FailureReason.TIMEOUT, *MOTION_REASONS,
    ),
    needs_robot=True,
)
class SetDown(_PlaceBase):
    """Set the held object down on the table in free space (to grasp it again): Place's checks on spots of the
    workspace clear of every object seen by ``clearance``, nearest the tool first, the object turned as held or
    half a turn round; writes where it came to rest to ``pose``.

    FAILURE: PLACE_BLOCKED (no free spot, or none the arm can reach and leave), and as Place.
    """

    def target_pose(self) -> tuple[Pose, Detection | None] | str:
        T_tool = self.cell.kinematics.fk(self.cell.robot.joint_positions())
        return Pose(float(T_tool[0, 3]), float(T_tool[1, 3])), None

    def covers_every_turn(self) -> bool:
        return False  # a set-down that found no spot says nothing about the grip

    def orientations(self, pose: Pose, held: Detection, T_tcp_obj: Mat4, surface_z_m: float
                     ) -> list[tuple[PlaceYaw, Mat4]] | str:
        spots = self._spots(pose, held)
        if not spots:
            return (f"no free spot on the table for the {held.size_m[0] * 1e3:.0f} mm object with "
                    f"{self.ports.require('clearance', float) * 1e3:.0f} mm round it")
        out: list[tuple[PlaceYaw, Mat4]] = []
        for x, y in spots:
            z = table_z_base(self.cell, x, y)
            out.extend(place_options(Pose(x, y), held, T_tcp_obj, float(held.size_m[2]), self._gap, z)[:2])
        return out

    def _spots(self, tool: Pose, held: Detection) -> list[tuple[float, float]]:
        """Spots (base x, y) of the workspace where the held object lies ``clearance`` clear of every object
        seen (circles round their footprints), within reach, nearest the tool first."""
        # deferred: a layering cycle (scene.format loads pydantic models; cheap, but only SetDown needs it)
        from bt_grasp.scene.format import place_xy_problem

        scene = self.cell.scene
        clearance = self.ports.require("clearance", float)
        seen = [d for d in (object_list(self.ports.get("objects")) or ()) if not same_object(d, held)]
        radius = math.hypot(float(held.size_m[0]), float(held.size_m[1])) / 2
        T_base_world = inv(np.asarray(scene.T_world_base(), dtype=float))
        ws = scene.workspace
        out: list[tuple[float, float, float]] = []
        for x in np.arange(ws.x_m[0] + radius, ws.x_m[1] - radius + 1e-9, SET_DOWN_STEP_M):
            for y in np.arange(ws.y_m[0] + radius, ws.y_m[1] - radius + 1e-9, SET_DOWN_STEP_M):
                if place_xy_problem(scene, (float(x), float(y))) is not None:
                    continue
                p = T_base_world @ np.array([x, y, 0.0, 1.0])
                gaps = [math.dist(p[:2], d.centroid_base_m[:2]) - radius
                        - math.hypot(float(d.size_m[0]), float(d.size_m[1])) / 2 for d in seen]
                if min(gaps, default=1.0) < clearance:
                    continue
                out.append((float(p[0]), float(p[1]), math.dist(p[:2], (tool.x_m, tool.y_m))))
        out.sort(key=lambda s: (s[2], s[0], s[1]))
        return [(x, y) for x, y, _ in out[:SET_DOWN_SPOTS]]

    def _remember_place(self) -> None:
        """Where the object came to rest: its centre's x, y and yaw as released (the table under it)."""
        assert self._T_place is not None
        T_obj = self._T_place @ self._T_tcp_obj
        pose = Pose(float(T_obj[0, 3]), float(T_obj[1, 3]), float(self._surface),
                    math.degrees(math.atan2(T_obj[1, 0], T_obj[0, 0])))
        self.ports.set("pose", pose)
        # what was tried on it goes with it (a grip no placement took is not taken again)
        was = ObjectSeen.of(self._held)
        centre = (pose.x_m, pose.y_m, float(self._surface) + float(self._held.size_m[2]) / 2)
        self.cell.attempts.moved(was, dataclasses.replace(was, centroid_m=centre, yaw_deg=pose.yaw_deg or 0.0))


@action(
    ports=[
        *PLAN_GRASP_PORTS,
        input_port("place_pose", Pose, description="where the object is to be set down afterwards (as Place's pose): "
                   "only a grasp whose grip makes that placement reachable is kept", required=True),
    ],
    reasons=PLAN_GRASP_REASONS,
    needs_robot=True,
)
class PlanRegrasp(PlanGrasp):
    """PlanGrasp for a regrasp: keep the first candidate whose approach is collision-free AND whose grip lets the
    object be set down at ``place_pose`` (some orientation its footprint allows has a release pose with an arm
    configuration clear of the scene seen, the object held as carried, and a pre-place pose above it; one not
    ruled out by an earlier attempt). FAILURE: as PlanGrasp (PLAN_FAILED when no grip makes the place
    reachable)."""

    def _try(self, rank: int, candidate: GraspCandidate) -> GraspPlan | None:
        plan = super()._try(rank, candidate)
        if plan is None:
            return None
        problem = self._placeable(candidate)
        if problem is not None:
            self._last = PathFailure(FailureReason.PLAN_FAILED, f"candidate {rank}: {problem}")
            return None
        return plan

    def _placeable(self, candidate: GraspCandidate) -> str | None:
        """Why the grip of ``candidate`` cannot place the object at ``place_pose`` (None: it can)."""
        target = self._target
        pose = self.ports.require("place_pose", Pose).in_base(self.cell.scene.T_world_base())
        surface = pose.z_m if pose.z_m is not None else table_z_base(self.cell, pose.x_m, pose.y_m)
        grip = held_offset(candidate, target)
        options = place_options(pose, target, grip, float(target.size_m[2]), RELEASE_GAP_M, surface)
        scene = self._place_scene(grip)
        checker = self.cell.planner.checker(scene, 0.0)
        kin = self.cell.kinematics
        for option, T_place in options:
            what = f"turned {math.degrees(option.turn_rad):.0f} deg"
            if self.cell.attempts.place_exclusion(target, grip, T_place, what) is not None:
                continue
            releases, _ = kin.ik_solutions(T_place, self._q, seeds=RELEASE_IK_SEEDS,
                                           max_solutions=RELEASE_IK_SOLUTIONS)
            for q_release in releases:
                if checker.is_valid(q_release) and kin.ik(_raised(T_place, APPROACH_M), q_release).ok:
                    return None
        return (f"with this grip no orientation of the object at {pose.x_m:.3f};{pose.y_m:.3f} has a release the "
                "arm reaches clear of what was seen")

    def _place_scene(self, grip: NDArray[np.float64]) -> PlanningScene:
        # deferred: scipy comes with it; a tree loads and validates without it
        from bt_grasp.motion.planning_scene import PlanningScene

        target = self._target
        others = [d for d in self._objects if not same_object(d, target)]
        obstacles = tuple(detection_box(d, f"object_{i}") for i, d in enumerate(others))
        box = detection_box(target, "held", margin_m=0.004)
        held = type(box).at("held", box.size_m, grip)
        return PlanningScene.from_scene(self.cell.scene, obstacles).with_attached(held, TCP_LINK)
