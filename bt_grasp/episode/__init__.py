"""Running episodes: the API below the command line (``bt-grasp run``, ``demo``, ``replay --resim``),
evaluation workers and notebooks all call. See docs/episode-api.md.

    from bt_grasp.episode import EpisodeRequest, WarmWorlds, goal_from_options, run_episode
    worlds = WarmWorlds()                     # keep the simulator and renderer between episodes
    goal = goal_from_options("pick", "red")   # or None: the scene's declared goal
    for seed in range(10):
        result = run_episode(EpisodeRequest(tree=..., scene=..., seed=seed, goal=goal), worlds=worlds)
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from bt_grasp.episode.episode import Episode, TickCallback, load_inputs, run_episode
    from bt_grasp.episode.request import (
        DEFAULT_MAX_TICKS,
        BlackboardValue,
        EpisodeRequest,
        parse_assignments,
        pick_request,
    )
    from bt_grasp.episode.result import EpisodeResult, Judged
    from bt_grasp.episode.worlds import FreshWorlds, WarmWorlds, WorldSource
    from bt_grasp.scene.goals import ClearGoal, Goal, PickGoal
    from bt_grasp.scene.run_goal import goal_for_run, goal_from_options

#: name -> the module defining it, imported on first use (issue 27): ``bt_grasp.episode.request`` alone is cheap,
#: and ``bt-grasp run --resident``'s client needs only it, not the episode and its simulator modules (~0.2-0.4 s)
_EXPORTS = {
    "Episode": "bt_grasp.episode.episode",
    "TickCallback": "bt_grasp.episode.episode",
    "load_inputs": "bt_grasp.episode.episode",
    "run_episode": "bt_grasp.episode.episode",
    "DEFAULT_MAX_TICKS": "bt_grasp.episode.request",
    "BlackboardValue": "bt_grasp.episode.request",
    "EpisodeRequest": "bt_grasp.episode.request",
    "parse_assignments": "bt_grasp.episode.request",
    "pick_request": "bt_grasp.episode.request",
    "EpisodeResult": "bt_grasp.episode.result",
    "Judged": "bt_grasp.episode.result",
    "FreshWorlds": "bt_grasp.episode.worlds",
    "WarmWorlds": "bt_grasp.episode.worlds",
    "WorldSource": "bt_grasp.episode.worlds",
    "ClearGoal": "bt_grasp.scene.goals",
    "Goal": "bt_grasp.scene.goals",
    "PickGoal": "bt_grasp.scene.goals",
    "goal_for_run": "bt_grasp.scene.run_goal",
    "goal_from_options": "bt_grasp.scene.run_goal",
}


def __getattr__(name: str) -> object:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)


__all__ = [
    "DEFAULT_MAX_TICKS",
    "BlackboardValue",
    "ClearGoal",
    "Episode",
    "EpisodeRequest",
    "EpisodeResult",
    "FreshWorlds",
    "Goal",
    "Judged",
    "PickGoal",
    "TickCallback",
    "WarmWorlds",
    "WorldSource",
    "goal_for_run",
    "goal_from_options",
    "load_inputs",
    "parse_assignments",
    "pick_request",
    "run_episode",
]
