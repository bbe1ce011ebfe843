"""Where an episode's simulated world comes from: built fresh, or a warm one reset for the next episode.

Building a World and rendering its first frame costs seconds (the renderer compiles its shaders on the
first capture); an evaluation worker pays that once with :class:`WarmWorlds` and resets the same world
(objects drawn again, arm home, clock at 0) for every following episode whose scene differs only in its
objects.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

from bt_grasp.scene_config import Scene

if TYPE_CHECKING:
    from bt_grasp.sim.world import World

log = logging.getLogger(__name__)


class WorldSource(Protocol):
    """Gives the world for one episode, as if built anew for ``(scene, seed)``."""

    def world_for(self, scene: Scene, seed: int, source: Path) -> World: ...


class FreshWorlds:
    """A new World per episode (one-off runs: ``bt-grasp run``)."""

    def world_for(self, scene: Scene, seed: int, source: Path) -> World:
        from bt_grasp.sim.world import World

        return World(scene, seed, source=source)


class WarmWorlds:
    """Keeps one world between episodes: reset when only the objects differ, rebuilt otherwise.

    ``built`` and ``resets`` count what happened (a worker can report its warm-start rate).
    """

    def __init__(self) -> None:
        self.world: World | None = None
        self.built = 0
        self.resets = 0

    def world_for(self, scene: Scene, seed: int, source: Path) -> World:
        if self.world is not None and self.world.can_reset_to(scene):
            self.world.reset(scene, seed, source=source)
            self.resets += 1
            return self.world
        from bt_grasp.sim.world import World

        if self.world is not None:
            log.info("scene %s differs in more than its objects: building a new world", source)
        self.world = World(scene, seed, source=source)
        self.built += 1
        return self.world
