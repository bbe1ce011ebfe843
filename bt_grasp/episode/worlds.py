"""Where an episode's simulated world comes from: built fresh, alone or beside a warm renderer.

Building a World is cheap (~0.05 s); its first picture is not (seconds on a CPU Vulkan driver: the renderer's
one-time set-up), unless the renderer is already warm in the process. :class:`WarmWorlds` keeps it warm
(``bt_grasp.sim.render_keeper``) and builds every episode's world afresh, so an evaluation worker pays the
set-up once and no simulation state ever carries over from one episode to the next.
"""

from __future__ import annotations

import gc
import logging
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

from bt_grasp.scene.format import Scene

if TYPE_CHECKING:
    from bt_grasp.sim.world import World

log = logging.getLogger(__name__)


_AT_EXIT: list[bool] = []  # whether the exit handler below is registered (once per process)


def _collect_frozen_at_exit() -> None:
    """At the interpreter's exit, unfreeze and collect what :class:`WarmWorlds` froze. Frozen objects are never
    collected, not even at exit: the planners' reference cycles were still alive when the interpreter tore down
    OMPL's bindings, and nanobind printed 28 lines of "leaked ... ompl" to the stderr of every script that ran an
    episode on warm worlds (the campaign workers left by ``os._exit``; a library's user has no such exit). An exit
    handler runs before the teardown, so the cycles go while their bindings still exist: nothing leaks, nothing is
    printed."""
    if _AT_EXIT:
        return
    import atexit

    def collect() -> None:
        gc.unfreeze()
        gc.collect()

    atexit.register(collect)
    _AT_EXIT.append(True)


class WorldSource(Protocol):
    """Gives the world for one episode, as if built anew for ``(scene, seed)``."""

    def world_for(self, scene: Scene, seed: int, source: Path) -> World: ...


class FreshWorlds:
    """A new World per episode (one-off runs: ``bt-grasp run``)."""

    def world_for(self, scene: Scene, seed: int, source: Path) -> World:
        from bt_grasp.sim.world import World

        return World(scene, seed, source=source)


class WarmWorlds:
    """A fresh World per episode beside a renderer kept warm for the process (campaign workers, the resident).

    The previous episode's world is released before the next is built. A world is never reused: PhysX keeps
    internal state across a reset (the order of its contact pairs among others), and a reset world could give
    the same episode a different tick stream (``bt_grasp.sim.render_keeper`` has the evidence). ``built``
    counts the worlds built. The objects alive once a world has been released (libraries, the warm renderer)
    are moved out of the garbage collector's way (``gc.freeze``) until the next release, which unfreezes them
    first (what an episode still held at the freeze must be collectable once it is dropped).
    """

    def __init__(self) -> None:
        self.world: World | None = None
        self.built = 0
        _collect_frozen_at_exit()

    def world_for(self, scene: Scene, seed: int, source: Path) -> World:
        from bt_grasp.sim.render_keeper import keep_renderer_warm
        from bt_grasp.sim.world import World

        keep_renderer_warm()
        if self.world is not None:  # release the previous episode's scene before building the next
            self.world = None
            # The last freeze also froze whatever of the previous episode was still held then (its Episode, and
            # through it its world: the caller builds the next Episode before dropping the last one); frozen
            # objects are never collected, so unfreeze first: otherwise a campaign worker kept every episode's
            # world, ~65 MiB each (1.1 GB after 8 episodes, 2.2 GB after 25). The full collection then scans
            # the libraries' ~130k objects again (~60 ms); freezing what survives it keeps the collections
            # *during* the episode from scanning them.
            gc.unfreeze()
            gc.collect()
            gc.freeze()
        self.world = World(scene, seed, source=source)
        self.built += 1
        return self.world
