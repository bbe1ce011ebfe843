"""Collision checking of arm configurations against a planning scene (pinocchio + coal).

The robot's geometry is the URDF's collision meshes/boxes, reduced like the kinematic model (fingers
locked at the model's opening). Self-collision pairs skip geometries on the same rigid body and the
pairs in ``DISABLED_COLLISION_PAIRS``; a link the list never names (``ee_link``) inherits the pairs of
the body it is fixed to. Robot-vs-scene pairs skip the shape's ``touch_links``; a safety margin
(``margin_m``) applies to robot-vs-scene pairs only (a configuration closer than the margin is invalid).
"""

from __future__ import annotations

import logging
import math
import warnings
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from bt_grasp.motion.kinematics import ArmKinematics, default_kinematics, other_robot
from bt_grasp.motion.planning_scene import Box, PlanningScene, Shape
from bt_grasp.robot_description import DISABLED_COLLISION_PAIRS, MAX_OPENING_M

log = logging.getLogger(__name__)

#: resolution of the final re-check of every path, rad (max joint step between checked states)
FINE_RESOLUTION_RAD = 0.01


@dataclass(frozen=True)
class PathCheck:
    """Outcome of checking a piecewise-linear joint path at a resolution."""

    ok: bool
    states_checked: int
    first_invalid_segment: int | None = None  # index i of the segment (qs[i], qs[i+1]) that failed
    first_invalid_q: NDArray[np.float64] | None = None


class RobotCollisionModel:
    """The robot's collision geometry and its self-collision pairs (shared by every scene's checker)."""

    def __init__(self, kin: ArmKinematics) -> None:
        self.kin = kin
        full_geom = pin.buildGeomFromUrdf(kin.full_model, str(kin.urdf_path), pin.GeometryType.COLLISION)
        _, self.geom_model = pin.buildReducedModel(
            kin.full_model, full_geom, list(kin.locked_joint_ids), kin.q_reference_full
        )
        self.geom_link: list[str] = [kin.model.frames[g.parentFrame].name for g in self.geom_model.geometryObjects]
        named = {n for pair in DISABLED_COLLISION_PAIRS for n in pair}
        disabled = {frozenset(p) for p in DISABLED_COLLISION_PAIRS}
        alias = {link: self._named_body(link, named) for link in set(self.geom_link)}
        self.self_pairs: list[tuple[int, int]] = []
        objs = self.geom_model.geometryObjects
        for a in range(len(objs)):
            for b in range(a + 1, len(objs)):
                if objs[a].parentJoint == objs[b].parentJoint:
                    continue  # the same rigid body
                if frozenset((alias[self.geom_link[a]], alias[self.geom_link[b]])) in disabled:
                    continue
                self.self_pairs.append((a, b))
        log.debug("robot collision model: %d geometries, %d self pairs", len(objs), len(self.self_pairs))

    def _named_body(self, link: str, named: set[str]) -> str:
        """The link itself if the disabled-pairs list names it, else the named body it is fixed to."""
        frames = self.kin.model.frames
        fid = self.kin.model.getFrameId(link)
        while frames[fid].name not in named and fid != 0:
            fid = frames[fid].parentFrame
        return frames[fid].name if fid != 0 else link


def _coal_shape(shape: Shape) -> coal.CollisionGeometry:
    if isinstance(shape, Box):
        return coal.Box(*shape.size_m)
    return coal.Cylinder(shape.radius_m, shape.height_m)


class CollisionChecker:
    """Validity and clearance of arm configurations in one planning scene."""

    def __init__(self, robot: RobotCollisionModel, scene: PlanningScene, *, margin_m: float = 0.0) -> None:
        if not (math.isfinite(margin_m) and margin_m >= 0.0):
            raise ValueError(f"collision margin must be >= 0, got {margin_m}")
        self.robot = robot
        self.scene = scene
        self.margin_m = float(margin_m)
        self.kin = robot.kin
        self.model = robot.kin.model
        self.data = self.model.createData()
        gm = robot.geom_model.copy()
        n_robot = gm.ngeoms
        for a, b in robot.self_pairs:
            gm.addCollisionPair(pin.CollisionPair(a, b))
        n_self = len(gm.collisionPairs)
        for shape in scene.shapes():
            obj = pin.GeometryObject(shape.name, 0, 0, pin.SE3(shape.T_base_shape), _coal_shape(shape))
            sid = gm.addGeometryObject(obj)
            for r in range(n_robot):
                if robot.geom_link[r] not in shape.touch_links:
                    gm.addCollisionPair(pin.CollisionPair(r, sid))
        attached_names: list[str] = []
        if scene.attached is not None:
            attached_names = [f"attached:{scene.attached.name}"]
            fid = self.model.getFrameId(scene.attached_link)
            frame = self.model.frames[fid]
            placement = frame.placement * pin.SE3(scene.attached.T_base_shape)
            obj = pin.GeometryObject(attached_names[0], frame.parentJoint, fid, placement,
                                     _coal_shape(scene.attached))
            aid = gm.addGeometryObject(obj)
            for sid in range(n_robot, aid):
                gm.addCollisionPair(pin.CollisionPair(sid, aid))
        self.geom_model = gm
        self.geom_data = gm.createData()
        for k in range(n_self, len(gm.collisionPairs)):
            self.geom_data.collisionRequests[k].security_margin = self.margin_m
        # GJK warm-started from the previous query's separating direction (pinocchio's default) answered
        # "no collision" for a carried box sunk 2 cm into a neighbour after a sweep of other queries (seen
        # with coal 3 / pinocchio 4.1); a checker's answer must not depend on what it was asked before.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            for request in self.geom_data.collisionRequests:
                request.enable_cached_gjk_guess = False
        # AABB culling before the narrow phase (coal's naive manager: 15-20 geometries make the O(n^2) box test
        # cheap): 2.4x faster per check than testing every pair, and the same answer on 1,800 states bisected
        # onto obstacle and margin boundaries (the pair list, margins and requests are geom_data's). The manager
        # keeps raw pointers to the models and datas, which this object owns for as long as it lives.
        self._broadphase = pin.BroadPhaseManager_NaiveCollisionManager(self.model, gm, self.geom_data)
        self._names = [g.name for g in gm.geometryObjects]
        self._links = robot.geom_link + list(scene.names) + attached_names

    def within_limits(self, q: NDArray[np.float64]) -> bool:
        return self.kin.within_limits(q)

    def in_collision(self, q: NDArray[np.float64]) -> bool:
        """True when any checked pair touches (or comes closer than the margin, for scene pairs)."""
        return bool(pin.computeCollisions(self.model, self.data, self._broadphase, np.asarray(q, dtype=float), True))

    def is_valid(self, q: NDArray[np.float64]) -> bool:
        """Finite, within the joint limits and collision-free."""
        q = np.asarray(q, dtype=float)
        if q.shape != (6,) or not np.all(np.isfinite(q)) or not self.kin.within_limits(q):
            return False
        return not self.in_collision(q)

    def colliding_pairs(self, q: NDArray[np.float64]) -> list[tuple[str, str]]:
        """Link or shape names of every pair in collision (for logs and failure reasons)."""
        pin.computeCollisions(self.model, self.data, self.geom_model, self.geom_data,
                              np.asarray(q, dtype=float), False)
        out = []
        for k, pair in enumerate(self.geom_model.collisionPairs):
            if self.geom_data.collisionResults[k].isCollision():
                out.append((self._links[pair.first], self._links[pair.second]))
        return out

    def min_distance(self, q: NDArray[np.float64]) -> float:
        """Smallest distance over all checked pairs, metres (<= 0 when something penetrates)."""
        pin.computeDistances(self.model, self.data, self.geom_model, self.geom_data, np.asarray(q, dtype=float))
        return float(min(r.min_distance for r in self.geom_data.distanceResults))

    def check_path(self, qs: NDArray[np.float64], resolution_rad: float = FINE_RESOLUTION_RAD) -> PathCheck:
        """Check every state of a piecewise-linear path, at most ``resolution_rad`` apart on every joint."""
        qs = np.atleast_2d(np.asarray(qs, dtype=float))
        if not (resolution_rad > 0 and math.isfinite(resolution_rad)):
            raise ValueError(f"resolution must be > 0 rad, got {resolution_rad}")
        if not self.is_valid(qs[0]):
            return PathCheck(False, 1, 0, qs[0].copy())
        checked = 1
        for i in range(len(qs) - 1):
            a, b = qs[i], qs[i + 1]
            n = max(1, math.ceil(float(np.max(np.abs(b - a))) / resolution_rad))
            for k in range(1, n + 1):
                q = a + (b - a) * (k / n)
                checked += 1
                if not self.is_valid(q):
                    return PathCheck(False, checked, i, q)
        return PathCheck(True, checked)


def robot_collision_model(opening_m: float = MAX_OPENING_M, urdf_path: Path | None = None) -> RobotCollisionModel:
    """The robot's collision model per gripper opening and robot description (``urdf_path``: another gripper's;
    None: bt_grasp's own), shared."""
    return _shared_collision_model(opening_m, other_robot(urdf_path))


@lru_cache(maxsize=4)
def _shared_collision_model(opening_m: float, urdf_path: Path | None) -> RobotCollisionModel:
    return RobotCollisionModel(default_kinematics(opening_m, urdf_path))


def collision_checker(scene: PlanningScene, margin_m: float = 0.0, opening_m: float = MAX_OPENING_M,
                      urdf_path: Path | None = None) -> CollisionChecker:
    """A cached checker per (scene, margin, opening, robot description): building one copies the robot's geometry."""
    return _shared_checker(scene, margin_m, opening_m, other_robot(urdf_path))


@lru_cache(maxsize=32)
def _shared_checker(scene: PlanningScene, margin_m: float, opening_m: float, urdf_path: Path | None
                    ) -> CollisionChecker:
    return CollisionChecker(robot_collision_model(opening_m, urdf_path), scene, margin_m=margin_m)
