"""Worlds built one after another beside a warm renderer (``WarmWorlds``: campaign workers, the resident) run an
episode exactly as a fresh process does, whatever ran before them in the process.

The regression this guards: a world *reset* between episodes kept PhysX's internal state, and the
pick-with-recovery seed-0 episode run three times in one reset world gave fingerprints A, A, B (they differed
from tick 494, when the fingers close on the box)."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from bt_grasp.episode import EpisodeRequest, FreshWorlds, WarmWorlds, WorldSource, run_episode
from bt_grasp.recording.fingerprint import Fingerprint, fingerprint_of_log
from bt_grasp.recording.reader import open_log

pytestmark = [pytest.mark.sim, pytest.mark.slow]

REPO = Path(__file__).resolve().parents[2]


def _run(worlds: WorldSource, tree: str, seed: int, log: Path) -> tuple[Fingerprint, float]:
    start = time.perf_counter()
    result = run_episode(EpisodeRequest(tree=REPO / tree, scene=REPO / "scenes/tabletop.yaml", seed=seed, log=log),
                         worlds=worlds)
    assert result.success, result
    return fingerprint_of_log(open_log(log)), time.perf_counter() - start


def test_the_same_episode_gives_the_same_run_every_time_in_a_warm_worker(tmp_path: Path) -> None:
    warm = WarmWorlds()
    prints = [_run(warm, "trees/pick_with_recovery.xml", 0, tmp_path / f"warm{i}.mcap")[0] for i in range(4)]
    fresh, _ = _run(FreshWorlds(), "trees/pick_with_recovery.xml", 0, tmp_path / "fresh.mcap")
    assert warm.built == 4
    for i, fp in enumerate(prints):
        difference = fresh.first_difference(fp)
        assert difference is None, f"warm episode {i}: {difference.describe()}"


def test_an_episode_after_another_matches_it_run_alone(tmp_path: Path) -> None:
    warm = WarmWorlds()
    _run(warm, "trees/pick.xml", 3, tmp_path / "warm3.mcap")  # another episode first: objects moved, arm moved
    after, _ = _run(warm, "trees/pick.xml", 4, tmp_path / "warm4.mcap")
    alone, _ = _run(FreshWorlds(), "trees/pick.xml", 4, tmp_path / "fresh4.mcap")
    difference = alone.first_difference(after)
    assert difference is None, difference.describe()
    assert len(after.ticks) > 300
