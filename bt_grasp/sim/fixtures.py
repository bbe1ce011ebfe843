"""Building a scene's fixtures (trays, bins, markers, walls) as static SAPIEN actors.

Each fixture kind describes itself as boxes (:meth:`parts`, in ``bt_grasp.scene.fixtures``); the default
builder makes one static actor per fixture from them: solid parts collide, flat parts (markers) are only
drawn. A kind that is not a set of static boxes (a conveyor) registers its own builder in :data:`BUILDERS`.
"""

from __future__ import annotations

from collections.abc import Callable

import sapien

from bt_grasp.scene.fixtures import Fixture
from bt_grasp.sim.poses import to_pose

#: friction of every fixture surface
FIXTURE_FRICTION = 0.6

Builder = Callable[[sapien.Scene, Fixture], sapien.Entity]


def build_static_parts(scene: sapien.Scene, fixture: Fixture) -> sapien.Entity:
    builder = scene.create_actor_builder()
    material = sapien.physx.PhysxMaterial(FIXTURE_FRICTION, FIXTURE_FRICTION, 0.0)
    for part in fixture.parts():
        half = [s / 2 for s in part.size_m]
        pose = to_pose(part.T_world_part)
        if part.solid:
            builder.add_box_collision(pose, half_size=half, material=material)
        render = sapien.render.RenderMaterial(base_color=[*part.rgb, 1.0], roughness=0.8, metallic=0.0)
        builder.add_box_visual(pose, half_size=half, material=render)
    return builder.build_static(name=f"fixture:{fixture.name}")


#: fixture kind -> how to build it (the default: static boxes from ``parts()``)
BUILDERS: dict[str, Builder] = {}


def build_fixture(scene: sapien.Scene, fixture: Fixture) -> sapien.Entity:
    return BUILDERS.get(fixture.kind, build_static_parts)(scene, fixture)
