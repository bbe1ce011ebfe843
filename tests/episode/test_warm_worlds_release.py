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
