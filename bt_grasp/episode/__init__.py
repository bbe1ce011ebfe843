"""Running episodes: the API below the command line (``bt-grasp run``, ``demo``, ``replay --resim``),
evaluation workers and notebooks all call. See docs/episode-api.md.

    from bt_grasp.episode import EpisodeRequest, WarmWorlds, goal_from_options, run_episode
    worlds = WarmWorlds()                     # keep the simulator and renderer between episodes
    goal = goal_from_options("pick", "red")   # or None: the scene's declared goal
    for seed in range(10):
        result = run_episode(EpisodeRequest(tree=..., scene=..., seed=seed, goal=goal), worlds=worlds)
"""

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
