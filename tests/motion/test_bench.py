"""The planning benchmark: a reproducible problem set and one JSON object from the command line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bt_grasp.bench.plan import make_problems, run_plan_bench


def test_problem_set_is_reproducible_and_large_enough(scene_config) -> None:  # type: ignore[no-untyped-def]
    a = make_problems(scene_config, 60, seed=0)
    b = make_problems(scene_config, 60, seed=0)
    assert len(a) == 60
    for pa, pb in zip(a, b, strict=True):
        np.testing.assert_array_equal(pa.q_start, pb.q_start)
        np.testing.assert_array_equal(pa.T_base_tcp_goal, pb.T_base_tcp_goal)
        assert pa.obstacles == pb.obstacles
    assert {p.kind for p in a} == {"above", "at"}
    assert {len(p.obstacles) for p in a} == {0, 1, 2, 3}
    json.dumps([p.to_json() for p in a])


def test_small_bench_summary(scene_config) -> None:  # type: ignore[no-untyped-def]
    summary = run_plan_bench(scene_config, count=6, seed=1).summary()
    assert summary["problems"] == 6
    # the seeded problem set is solvable and the planner's budget counts checks, not seconds: every problem is
    # solved on any machine, whatever its load
    assert summary["success_rate"] == 1.0 and summary["statuses"] == {"ok": 6}, summary
    for key in ("plan_ms_median", "ik_ms_median", "traj_ms_median", "path_length_rad_median",
                "traj_duration_s_median"):
        assert 0.0 < summary[key] < 60_000, (key, summary)  # type: ignore[operator]
    assert summary["plan_ms_p95"] >= summary["plan_ms_median"]  # type: ignore[operator]
    assert 0.0 <= summary["direct_fraction"] <= 1.0  # type: ignore[operator]


def test_cli_prints_exactly_one_json_object(capsys: pytest.CaptureFixture[str]) -> None:
    from bt_grasp.cli.main import main

    code = main(["bench", "plan", "--problems", "4", "--seed", "2", "--json"])
    assert code == 0
    out = capsys.readouterr().out.strip()
    summary = json.loads(out)
    assert out.count("\n") == 0
    for key in ("problems", "success_rate", "plan_ms_median", "plan_ms_p95", "ik_ms_median", "traj_ms_median"):
        assert key in summary
    assert summary["problems"] == 4


def test_cli_rejects_an_unknown_planner(capsys: pytest.CaptureFixture[str]) -> None:
    from bt_grasp.cli.main import main

    assert main(["bench", "plan", "--problems", "2", "--planner", "Nope"]) == 2
    assert "Nope" in capsys.readouterr().err


def test_labels_count_success_over_feasible_problems(scene_config) -> None:  # type: ignore[no-untyped-def]
    from bt_grasp.bench.plan import feasibility_labels

    labels = feasibility_labels(0)
    assert len(labels) == 60 and [i for i, ok in labels.items() if not ok] == [16, 18, 31]
    assert feasibility_labels(1) == {}
    summary = run_plan_bench(scene_config, count=3, seed=0).summary()
    assert summary["labelled_problems"] == 3 and summary["feasible_problems"] == 3
    assert summary["success_over_feasible"] == 1.0
