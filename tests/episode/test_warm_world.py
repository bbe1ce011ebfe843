"""A warm world reset for the next episode runs it as a freshly built world would: same tick stream."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_grasp.episode import EpisodeRequest, FreshWorlds, WarmWorlds, WorldSource, run_episode
from bt_grasp.recording.compare import compare_tick_streams
from bt_grasp.recording.reader import open_log

pytestmark = [pytest.mark.sim, pytest.mark.slow]

REPO = Path(__file__).resolve().parents[2]


def _run(worlds: WorldSource, seed: int, log: Path) -> None:
    run_episode(EpisodeRequest(tree=REPO / "trees/pick.xml", scene=REPO / "scenes/tabletop.yaml", seed=seed,
                               log=log, max_ticks=300), worlds=worlds)


def test_a_reset_world_gives_the_fresh_worlds_tick_stream(tmp_path: Path) -> None:
    warm = WarmWorlds()
    _run(warm, 3, tmp_path / "warm3.mcap")  # builds the world, moves the arm, perhaps an object
    _run(warm, 4, tmp_path / "warm4.mcap")  # resets it for seed 4
    _run(FreshWorlds(), 4, tmp_path / "fresh4.mcap")
    assert (warm.built, warm.resets) == (1, 1)
    fresh, reset = open_log(tmp_path / "fresh4.mcap"), open_log(tmp_path / "warm4.mcap")
    assert len(fresh.ticks) == len(reset.ticks) == 300
    assert compare_tick_streams(fresh.ticks, reset.ticks) is None
