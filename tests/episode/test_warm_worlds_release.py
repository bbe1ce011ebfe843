"""WarmWorlds moves what outlives a released world out of the garbage collector's way (``gc.freeze``, issue 27:
a full collection per episode cost ~60 ms). Worlds built after that must still be released: a campaign worker's
memory stays flat only if every episode's world is freed before the next one is built."""

from __future__ import annotations

import gc
import weakref
from collections.abc import Iterator
from pathlib import Path

import pytest

from bt_grasp.episode import WarmWorlds
from bt_grasp.scene.format import load_scene

pytestmark = [pytest.mark.sim]

SCENE = Path(__file__).resolve().parents[2] / "scenes" / "tabletop.yaml"


@pytest.fixture
def unfrozen() -> Iterator[None]:
    yield
    gc.unfreeze()  # the rest of the test session collects as before


def test_every_released_world_is_collected_after_the_freeze(unfrozen: None) -> None:
    scene = load_scene(SCENE)
    worlds = WarmWorlds()
    released = []
    for seed in range(4):
        world = worlds.world_for(scene, seed, SCENE)
        released.append(weakref.ref(world))
        del world
    assert gc.get_freeze_count() > 0  # the freeze happened (from the second world on)
    assert [ref() is None for ref in released] == [True, True, True, False]  # only the current world is alive


def test_a_world_still_held_at_the_next_release_is_collected_later(unfrozen: None) -> None:
    """As a worker runs them: the next episode is built while the last one (holding its world, in reference
    cycles) is still referenced, and dropped after. Each world must be collected at a later release; with a
    freeze that was never undone, every one of them stayed (the worker grew ~65 MiB an episode)."""
    scene = load_scene(SCENE)
    worlds = WarmWorlds()
    released = []
    episode: list[object] | None = None
    for seed in range(4):
        world = worlds.world_for(scene, seed, SCENE)  # the previous episode is still held here
        released.append(weakref.ref(world))
        episode = [world]
        episode.append(episode)  # an episode object in a reference cycle, holding its world
        del world
    assert episode is not None
    # worlds 0 and 1 were dropped before the releases of seeds 2 and 3; world 2 is dropped, not yet released
    assert [ref() is None for ref in released[:2]] == [True, True]
