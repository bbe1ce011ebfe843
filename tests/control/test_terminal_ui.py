"""The terminal front end's logic through Textual's Pilot (no simulator: the stand-in tree of stand_ins.py).

Key by key: the run starts paused before tick 1; ``s`` steps one tick; ``b`` sets an entry (a bad value gets one
sentence); ``o`` chooses an object; ``x`` fires a fault; ``f`` toggles break-on-failure; ``n`` steps N; ``R``
restarts with the next seed (the breakpoints go on); ``p`` runs on; ``q`` stops the run (its log would be
finished) and exits.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable, Mapping
from typing import Any

import pytest

from bt_grasp.cli.interactive_ui import InteractiveApp, Session, parse_prompt, status_line, tree_text
from bt_grasp.control import ChooseObject, Controller, FireFault, RunState, SetBlackboard, Step
from tests.control.stand_ins import build, run


class StandInEpisodes:
    """Runs the stand-in tree under the app's controller, as bt-grasp run runs an episode."""

    def __init__(self) -> None:
        self.seeds: list[int] = []
        self.fired: list[tuple[str, dict[str, Any], int]] = []
        self.trees: list[Any] = []

    def fire(self, kind: str, params: Mapping[str, Any], tick: int) -> str:
        self.fired.append((kind, dict(params), tick))
        return f"{kind} armed"

    def __call__(self, controller: Controller, seed: int, number: int) -> str:
        self.seeds.append(seed)
        tree, stepper = build()
        self.trees.append(tree)
        controller.attach(tree, stepper.now_ns, fire_fault=self.fire)
        outcome, _ = run(tree, stepper, controller)
        return f"{outcome.status} after {outcome.ticks} ticks, seed {seed}"


async def _until(app: InteractiveApp, pilot: Any, check: Callable[[RunState], bool], what: str) -> RunState:
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        state = app.controller.state()
        if check(state):
            await pilot.pause()
            return state
        await asyncio.sleep(0.01)
    raise AssertionError(f"timed out waiting for {what}; state {app.controller.state()}")


async def _answer(pilot: Any, key: str, text: str) -> None:
    await pilot.press(key)
    await pilot.press(*text)
    await pilot.press("enter")


def test_the_keys_drive_the_run() -> None:
    episodes = StandInEpisodes()

    async def drive() -> InteractiveApp:
        app = InteractiveApp(Session(episodes, seed=7), refresh_s=0.02)
        async with app.run_test(size=(140, 40)) as pilot:
            state = await _until(app, pilot, lambda s: s.paused and s.tick == 0 and bool(s.nodes), "the start")
            assert "PAUSED: paused before the first tick" in status_line(state, 0)
            await pilot.press("s")
            state = await _until(app, pilot, lambda s: s.paused and s.tick == 1, "tick 1")
            assert [(d.index, d.label) for d in state.detections] == [(0, "red"), (1, "blue")]
            assert "See  SUCCESS" in tree_text(state).plain
            await _answer(pilot, "b", "height=high")
            state = await _until(app, pilot, lambda s: "does not fit" in s.message, "the refusal")
            assert ("height", "0.05") in state.blackboard
            await _answer(pilot, "b", "height=0.08")
            await _answer(pilot, "o", "1")
            await _answer(pilot, "x", "frame_drop frames=2")
            await pilot.press("f")
            state = await _until(app, pilot, lambda s: len(s.interventions) == 3 and s.break_on_failure,
                                 "three interventions and the failure breakpoint")
            assert [(r.tick, r.command["kind"], r.source) for r in state.interventions] == [
                (1, "set_blackboard", "terminal"), (1, "choose_object", "terminal"), (1, "fire_fault", "terminal")]
            await _answer(pilot, "n", "2")
            state = await _until(app, pilot, lambda s: s.paused and s.tick == 3, "tick 3")
            assert state.pause_reason == "stepped to tick 3"
            await pilot.press("R")  # restart with the next seed: episode 2 starts paused
            await _until(app, pilot, lambda s: app.number == 1 and s.paused and s.tick == 0, "episode 2")
            assert episodes.trees[0].root_blackboard.get("target").label == "blue"
            assert episodes.fired == [("frame_drop", {"frames": 2}, 1)]
            await pilot.press("p")  # the breakpoints go on with the episode: it holds at Check's failure
            state = await _until(app, pilot, lambda s: s.paused and s.tick == 1, "the failure breakpoint")
            assert state.pause_reason == "breakpoint fail: Check::4 failed (FLAKY)"
            await pilot.press("f", "p")
            await _until(app, pilot, lambda s: s.finished, "the end of episode 2")
            await pilot.pause(0.1)
            assert "finished: SUCCESS after 5 ticks, seed 8" in str(app.query_one("#message").render())
            await pilot.press("q")
            await pilot.pause()
        return app

    app = asyncio.run(drive())
    assert episodes.seeds == [7, 8] and app.error is None and app.done.is_set()
    assert app.summaries == ["RUNNING after 3 ticks, seed 7", "SUCCESS after 5 ticks, seed 8"]


def test_quit_stops_a_paused_run_and_finishes_it() -> None:
    episodes = StandInEpisodes()

    async def drive() -> InteractiveApp:
        app = InteractiveApp(Session(episodes, seed=0), refresh_s=0.02)
        async with app.run_test() as pilot:
            await _until(app, pilot, lambda s: s.paused, "the start")
            await pilot.press("q")
            for _ in range(200):
                if app.done.is_set():
                    break
                await asyncio.sleep(0.01)
        return app

    app = asyncio.run(drive())
    assert app.done.is_set() and app.summaries == ["RUNNING after 0 ticks, seed 0"]
    assert [r.command["kind"] for r in app.controller.interventions] == ["stop"]


@pytest.mark.parametrize(
    ("key", "text", "command"),
    [
        ("n", "3", Step(3)),
        ("b", "lift_height = 0.2", SetBlackboard("lift_height", "0.2")),
        ("o", "2", ChooseObject(2, "target")),
        ("o", "green object", ChooseObject("green", "object")),
        ("x", "gripper_slip force_n=2.5,friction=0.1", FireFault("gripper_slip", {"force_n": 2.5, "friction": 0.1})),
    ],
)
def test_prompt_answers(key: str, text: str, command: object) -> None:
    assert parse_prompt(key, text) == command


@pytest.mark.parametrize(
    ("key", "text", "problem"),
    [("n", "two", "'two' is not a number of ticks"), ("n", "0", "step at least 1 tick"),
     ("b", "novalue", "expected KEY=VALUE, got 'novalue'"), ("o", "", "expected INDEX|LABEL [ENTRY]"),
     ("x", "frame_drop frames", "expected KEY=VALUE, got 'frames'")],
)
def test_an_answer_that_cannot_be_read_is_one_sentence(key: str, text: str, problem: str) -> None:
    with pytest.raises(ValueError, match=problem.replace("[", r"\[").replace("|", r"\|")):
        parse_prompt(key, text)
