"""`bt-grasp bench budget`'s stage clock: exclusive time per stage, and timers that leave nothing behind."""

from __future__ import annotations

import time

import pytest

from bt_grasp.bench.budget import StageClock, timed_seams


def test_a_stage_inside_another_counts_once_for_the_inner_stage() -> None:
    clock = StageClock()

    def render() -> None:
        time.sleep(0.02)

    timed_render = clock.wrap("rendering", render)

    def perceive() -> str:
        timed_render()
        time.sleep(0.01)
        return "seen"

    start = time.perf_counter()
    assert clock.wrap("perception", perceive)() == "seen"  # results pass through
    outer = time.perf_counter() - start
    assert clock.calls["rendering"] == 1 and clock.calls["perception"] == 1
    assert clock.totals["rendering"] >= 0.02 and clock.totals["perception"] >= 0.01
    # the two add up to the outer call once (the picture is not counted again inside perception)
    assert clock.totals["rendering"] + clock.totals["perception"] == pytest.approx(outer, abs=2e-3)


def test_a_stage_that_raises_is_still_timed() -> None:
    clock = StageClock()

    def fail() -> None:
        raise ValueError("no frame")

    with pytest.raises(ValueError):
        clock.wrap("perception", fail)()
    assert clock.calls["perception"] == 1 and not clock._stack


@pytest.mark.sim
def test_the_timers_are_removed_afterwards() -> None:
    from bt_grasp.sim.world import World
    from bt_grasp.tree.loader import LoadedTree

    before = (World.step, LoadedTree.tick)
    with timed_seams(StageClock()):
        assert World.step is not before[0]
    assert (World.step, LoadedTree.tick) == before
