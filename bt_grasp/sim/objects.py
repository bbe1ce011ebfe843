"""Building the scene's objects and drawing their poses from a seed (non-overlapping)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sapien

from bt_grasp.errors import ConfigError
from bt_grasp.geometry import Mat4, make_T, rot_z
from bt_grasp.scene_config import SceneObject
from bt_grasp.sim.poses import to_pose

# a cylinder in PhysX lies along x; rotate it to stand along z
_CYLINDER_UPRIGHT = sapien.Pose(q=[np.cos(np.pi / 4), 0.0, np.sin(np.pi / 4), 0.0])


@dataclass(frozen=True)
class PlacedObject:
    spec: SceneObject
    T_world_object: Mat4


def footprint_radius_m(obj: SceneObject) -> float:
    if obj.shape == "box":
        return float(np.hypot(obj.size_m[0], obj.size_m[1]) / 2)
    return float(obj.size_m[0])


def draw_poses(
    objects: tuple[SceneObject, ...], rng: np.random.Generator, table_top_z_m: float, source: str = "scene"
) -> list[PlacedObject]:
    """Draw each object's pose within its randomisation ranges, rejecting overlaps (up to 200 tries)."""
    placed: list[PlacedObject] = []
    for obj in objects:
        r = footprint_radius_m(obj)
        for _attempt in range(200):
            x = obj.pose.xy_m[0] + rng.uniform(*obj.randomize.x_m)
            y = obj.pose.xy_m[1] + rng.uniform(*obj.randomize.y_m)
            yaw = np.deg2rad(obj.pose.yaw_deg + rng.uniform(*obj.randomize.yaw_deg))
            clear = all(
                np.hypot(x - p.T_world_object[0, 3], y - p.T_world_object[1, 3]) > r + footprint_radius_m(p.spec) + 0.01
                for p in placed
            )
            if clear:
                break
        else:
            raise ConfigError(source, f"cannot place object '{obj.name}' without overlapping others", "objects")
        z = table_top_z_m + obj.height_m / 2
        placed.append(PlacedObject(obj, make_T(rot_z(yaw), [x, y, z])))
    return placed


def build_object(scene: sapien.Scene, placed: PlacedObject) -> sapien.Entity:
    obj = placed.spec
    builder = scene.create_actor_builder()
    material = sapien.physx.PhysxMaterial(obj.friction, obj.friction, 0.0)
    render_material = sapien.render.RenderMaterial(base_color=[*obj.rgb, 1.0], roughness=0.7, metallic=0.0)
    if obj.shape == "box":
        half = [s / 2 for s in obj.size_m]
        builder.add_box_collision(half_size=half, material=material)
        builder.add_box_visual(half_size=half, material=render_material)
    elif obj.shape == "cylinder":
        radius, height = obj.size_m
        builder.add_cylinder_collision(_CYLINDER_UPRIGHT, radius=radius, half_length=height / 2, material=material)
        builder.add_cylinder_visual(_CYLINDER_UPRIGHT, radius=radius, half_length=height / 2, material=render_material)
    else:
        builder.add_sphere_collision(radius=obj.size_m[0], material=material)
        builder.add_sphere_visual(radius=obj.size_m[0], material=render_material)
    density = obj.mass_kg / _volume_m3(obj)
    for shape in builder.collision_records:
        shape.density = density
    builder.set_initial_pose(to_pose(placed.T_world_object))
    actor = builder.build(name=obj.name)
    return actor


def _volume_m3(obj: SceneObject) -> float:
    if obj.shape == "box":
        return float(np.prod(obj.size_m))
    if obj.shape == "cylinder":
        return float(np.pi * obj.size_m[0] ** 2 * obj.size_m[1])
    return float(4.0 / 3.0 * np.pi * obj.size_m[0] ** 3)
