"""The conveyor in the simulator: a static frame and a chain of thin kinematic slats moving at belt speed.

PhysX moves a kinematic body towards its target each step with the velocity that reaches it, so objects
resting on a slat are carried by contact friction exactly as by a real belt (they slip if accelerated
faster than friction allows, they can be held back by a gripper). The slats run along the belt; a slat that
has left the downstream end by one pitch goes back under the upstream end, as a real belt's return run
does, so the chain never ends. Nothing touches the objects but physics.
"""

from __future__ import annotations

import numpy as np
import sapien

from bt_grasp.scene.conveyor import SLAT_PITCH_M, SLAT_THICKNESS_M, Conveyor
from bt_grasp.sim.fixtures import BUILDERS, FIXTURE_FRICTION
from bt_grasp.sim.objects import PlacedObject
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
