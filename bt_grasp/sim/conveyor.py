"""The conveyor in the simulator: a static frame and a chain of thin kinematic slats moving at belt speed.

PhysX moves a kinematic body towards its target each step with the velocity that reaches it, so objects
resting on a slat are carried by contact friction exactly as by a real belt (they slip if accelerated
faster than friction allows, they can be held back by a gripper). The slats run along the belt; a slat that
has left the downstream end by one pitch goes back under the upstream end, as a real belt's return run
does, so the chain never ends. Nothing touches the objects but physics.

A belt's encoder (:class:`BeltEncoder`) counts the belt's own travel, as an encoder on its drive does: whole
counts, never an object's pose. A belt's feed (:class:`BeltFeed`) sets the objects of the scene's ``feed`` down
on the belt at its upstream end when the belt has run the drawn distance: each is a new body, standing at rest
where it enters (primitives exactly resting, meshes dropped from 2 mm), which the belt then accelerates by
friction as a real belt does an item dropped on it; none is moved by code after that.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import sapien

from bt_grasp.geometry import make_T, rot_z
from bt_grasp.scene.conveyor import SLAT_PITCH_M, SLAT_THICKNESS_M, Conveyor, Feed
from bt_grasp.scene.layout import draw_rest
from bt_grasp.sim.fixtures import BUILDERS, FIXTURE_FRICTION
from bt_grasp.sim.objects import PlacedObject, resting_z_m
from bt_grasp.sim.poses import to_pose

#: gap between neighbouring slats, m
_SLAT_GAP_M = 0.001
_SLAT_RGB = (0.12, 0.12, 0.13)


def build_conveyor_frame(scene: sapien.Scene, fixture: Conveyor) -> sapien.Entity:
    """The static frame under the belt (its top ``SLAT_THICKNESS_M`` below the belt surface)."""
    builder = scene.create_actor_builder()
    frame_h = fixture.height_m - SLAT_THICKNESS_M
    half = [fixture.length_m / 2, fixture.width_m / 2 + 0.01, frame_h / 2]
    pose = to_pose(fixture.T_world_fixture(frame_h / 2))
    material = sapien.physx.PhysxMaterial(FIXTURE_FRICTION, FIXTURE_FRICTION, 0.0)
    builder.add_box_collision(pose, half_size=half, material=material)
    render = sapien.render.RenderMaterial(base_color=[*fixture.rgb, 1.0], roughness=0.8, metallic=0.0)
    builder.add_box_visual(pose, half_size=half, material=render)
    return builder.build_static(name=f"fixture:{fixture.name}")


BUILDERS["conveyor"] = build_conveyor_frame  # type: ignore[assignment]


class ConveyorBelt:
    """The moving slats of one conveyor; :meth:`before_step` advances them by one physics step."""

    def __init__(self, scene: sapien.Scene, spec: Conveyor) -> None:
        self.spec = spec
        self._count = int(np.ceil(spec.length_m / SLAT_PITCH_M)) + 1
        self._sign = 1.0 if spec.direction == "forward" else -1.0
        self._T_world_fixture = spec.T_world_fixture(spec.height_m - SLAT_THICKNESS_M / 2)
        self._k = np.arange(self._count, dtype=float)
        self._origin = self._T_world_fixture[:3, 3].copy()
        self._axis = self._T_world_fixture[:3, 0].copy()
        self._q = to_pose(self._T_world_fixture).q
        material = sapien.physx.PhysxMaterial(spec.friction, spec.friction, 0.0)
        render = sapien.render.RenderMaterial(base_color=[*_SLAT_RGB, 1.0], roughness=0.9, metallic=0.0)
        half = [(SLAT_PITCH_M - _SLAT_GAP_M) / 2, spec.width_m / 2, SLAT_THICKNESS_M / 2]
        self.slats: list[sapien.Entity] = []
        self._bodies: list[sapien.physx.PhysxRigidDynamicComponent] = []
        for k in range(self._count):
            builder = scene.create_actor_builder()
            builder.add_box_collision(half_size=half, material=material)
            builder.add_box_visual(half_size=half, material=render)
            builder.set_initial_pose(self._pose(k, 0.0))
            entity = builder.build_kinematic(name=f"{spec.name}/slat{k}")
            self.slats.append(entity)
            self._bodies.append(entity.find_component_by_type(sapien.physx.PhysxRigidDynamicComponent))
        self.travel_m = 0.0  # how far the belt has moved since the episode started

    def _local_x(self, travel_m: float) -> np.ndarray:
        """Every slat's centre along the belt after the belt moved ``travel_m`` (wrapped onto the chain)."""
        u = (self._k * SLAT_PITCH_M + self._sign * travel_m) % (self._count * SLAT_PITCH_M)
        return np.asarray(u - self.spec.length_m / 2 - SLAT_PITCH_M / 2)

    def _pose(self, k: int, travel_m: float) -> sapien.Pose:
        return self._pose_at(float(self._local_x(travel_m)[k]))

    def _pose_at(self, x_local: float) -> sapien.Pose:
        return sapien.Pose(self._origin + x_local * self._axis, self._q)

    def before_step(self, dt_s: float) -> None:
        """Move every slat by speed * dt: kinematic targets (carrying objects), or a jump back under the
        upstream end for the slat whose turn it is (nothing rides on it there)."""
        x_old = self._local_x(self.travel_m)
        self.travel_m += self.spec.speed_m_s * dt_s
        x_new = self._local_x(self.travel_m)
        wrapped = np.abs(x_new - x_old) > SLAT_PITCH_M
        for k, (entity, body) in enumerate(zip(self.slats, self._bodies, strict=True)):
            pose = self._pose_at(float(x_new[k]))
            if wrapped[k]:  # wrapped round: back to the start under the belt
                entity.set_pose(pose)
            else:
                body.set_kinematic_target(pose)

    def reset(self) -> None:
        self.travel_m = 0.0
        for k, entity in enumerate(self.slats):
            entity.set_pose(self._pose(k, 0.0))


class BeltEncoder:
    """Implements :class:`bt_grasp.interfaces.Encoder` from the belt's own motion: the whole counts of its travel."""

    def __init__(self, belt: ConveyorBelt) -> None:
        assert belt.spec.encoder is not None
        self._belt = belt
        self.counts_per_m = float(belt.spec.encoder.counts_per_m)

    def counts(self) -> int:
        return math.floor(self._belt.travel_m * self.counts_per_m + 1e-9)


@dataclass(frozen=True)
class Entry:
    """One object of a feed: it enters once the belt has run ``travel_m``, set down as ``placed`` says."""

    travel_m: float
    placed: PlacedObject


def draw_entries(spec: Conveyor, feed: Feed, rng: np.random.Generator) -> list[Entry]:
    """Every entry of a feed, drawn from the run's ``BELT_FEED`` stream in order: per entry its spacing behind the
    one before (none for the first), its template, its place across the belt, its yaw and (a mesh set down
    ``stable`` or ``any_stable``) its rest pose."""
    entries: list[Entry] = []
    travel = spec.speed_m_s * feed.first_s  # the belt's travel when the first enters (it runs at a constant speed)
    T_world_fixture = spec.T_world_fixture()
    along = -spec.sign * (spec.length_m / 2 - feed.entry_m)  # on the fixture's x axis, from its centre
    for k in range(feed.count):
        if k:
            travel += float(rng.uniform(*feed.spacing_m))
        template = feed.objects[int(rng.integers(len(feed.objects)))]
        across = float(rng.uniform(*feed.across_m))
        yaw = np.deg2rad(spec.yaw_deg + float(rng.uniform(*feed.yaw_deg)))
        R_rest = draw_rest(template, rng) if template.is_mesh and template.rest_pose != "modelled" else None
        xy = (T_world_fixture @ np.array([along, across, 0.0, 1.0]))[:2]
        T = make_T(rot_z(yaw), [float(xy[0]), float(xy[1]), resting_z_m(template, spec.surface_z_m, R_rest)])
        if R_rest is not None:
            T[:3, :3] = T[:3, :3] @ R_rest
        entries.append(Entry(travel, PlacedObject(template.model_copy(update={"name": f"{template.name}_{k}"}), T)))
    return entries


class BeltFeed:
    """The entries of one belt's feed still to come; :meth:`due` hands over those whose travel the belt has run."""

    def __init__(self, belt: ConveyorBelt, rng: np.random.Generator) -> None:
        assert belt.spec.feed is not None
        self._belt = belt
        self._coming = draw_entries(belt.spec, belt.spec.feed, rng)

    def due(self) -> list[PlacedObject]:
        out = []
        while self._coming and self._belt.travel_m >= self._coming[0].travel_m - 1e-12:
            out.append(self._coming.pop(0).placed)
        return out

    @property
    def remaining(self) -> int:
        return len(self._coming)


def belts_for(scene: sapien.Scene, fixtures: tuple[object, ...]) -> list[ConveyorBelt]:
    return [ConveyorBelt(scene, f) for f in fixtures if isinstance(f, Conveyor)]


def support_height_m(fixtures: tuple[object, ...], xy: tuple[float, float]) -> float:
    """Height of the surface under a world (x, y): a conveyor's belt there, else the table top (0)."""
    for f in fixtures:
        if isinstance(f, Conveyor) and f.on_belt(xy):
            return f.surface_z_m
    return 0.0


def on_supports(placed: list[PlacedObject], fixtures: tuple[object, ...]) -> list[PlacedObject]:
    """Objects drawn over a conveyor's belt start on its surface (drawn poses stand on the table top)."""
    out = []
    for p in placed:
        T = p.T_world_object.copy()
        T[2, 3] += support_height_m(fixtures, (float(T[0, 3]), float(T[1, 3])))
        out.append(PlacedObject(p.spec, T))
    return out
