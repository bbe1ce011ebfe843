"""`bench tasks --task T` and `eval run --tree trees/T.xml --scene scenes/T.yaml --seeds N` stand for the same
episodes (issue 24's one entry point): the README and docs/campaigns.md say a user evaluating one task gets, from
`eval run`, the episodes the developer benchmark runs. Checked for every shipped task without the simulator: the
requests `bench tasks` makes are captured, and compared with the campaign `eval run` writes and loads."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

REPO = Path(__file__).resolve().parents[1]
DOCS = (REPO / "docs" / "campaigns.md").read_text()


def _resolved(path: Any) -> Path | None:
    return Path(path).resolve() if path is not None else None


def test_bench_tasks_and_eval_run_stand_for_the_same_episodes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import bt_grasp.episode as episode_package
    from bt_grasp.bench.tasks import TASKS, run_task_bench
    from bt_grasp.campaign.spec import load_campaign, write_options_campaign
    from bt_grasp.defaults import DEFAULT_MAX_TICKS
    from bt_grasp.perception.calibration_file import calibration_for_scene
    from bt_grasp.scene.format import load_scene

    requests: list[Any] = []

    def capture(request: Any, worlds: Any = None) -> Any:  # what run_episode was asked to run
        requests.append(request)
        also = tuple(SimpleNamespace(success=True) for _ in request.also_judge)  # what a clear task judges beside
        return SimpleNamespace(success=True, sim_time_s=1.0, reason=None, tree_status="SUCCESS", also_judged=also,
                               judged=SimpleNamespace(failed_condition=None))

    monkeypatch.setattr(episode_package, "run_episode", capture)
    monkeypatch.setattr(episode_package, "WarmWorlds", lambda: None)
    monkeypatch.chdir(tmp_path)
    assert len(TASKS) >= 5
    for task in TASKS:
        requests.clear()
        run_task_bench([task], 3, first_seed=5, root=REPO)
        tree, scene = task.paths(REPO)
        # a task with a longer limit than eval run's default is run with --max-ticks, as docs/campaigns.md says
        longer = None if task.max_ticks == DEFAULT_MAX_TICKS else task.max_ticks
        if longer is not None:
            assert f"`{task.name}` needs" in DOCS and f"--max-ticks {longer}`" in DOCS, task.name
        campaign = load_campaign(write_options_campaign([tree], [scene], 3, 5, None, tmp_path / task.name,
                                                        max_ticks=longer), check_inputs=False)
        episodes = campaign.episodes()
        bench = [(_resolved(r.tree), _resolved(r.scene), r.seed, dict(r.blackboard), r.max_ticks, r.goal, r.faults,
                  r.inject) for r in requests]
        evaluated = [(_resolved(e.request.tree), _resolved(e.request.scene), e.seed, dict(e.request.blackboard),
                      e.max_ticks, e.request.goal, e.request.faults, e.request.inject) for e in episodes]
        assert bench == evaluated, task.name
        assert [r.seed for r in requests] == [5, 6, 7]
        for request, episode in zip(requests, episodes, strict=True):  # the same calibration, once resolved
            used, _ = calibration_for_scene(load_scene(request.scene), request.scene, request.calibration)
            assert _resolved(used) == _resolved(episode.request.calibration), task.name
