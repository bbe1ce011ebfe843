"""The results file is the durable record: rows on disk as episodes finish, a torn row cut off, resume
runs only what is missing, a row is never written twice, rows of other inputs are refused."""

from __future__ import annotations

import json
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import pytest

from bt_grasp.campaign.results import read_rows
from bt_grasp.campaign.runner import CampaignIncomplete, EpisodeError, run_campaign
from bt_grasp.campaign.spec import Campaign, PlannedEpisode, load_campaign
from bt_grasp.errors import InputError

REPO = Path(__file__).resolve().parents[2]


def _campaign(tmp_path: Path, seeds: int = 5) -> Campaign:
    path = tmp_path / "c.yaml"
    path.write_text(
        f"name: c\ntrees: [{REPO / 'trees/pick.xml'}]\nscenes: [{REPO / 'scenes/tabletop.yaml'}]\n"
        f"seeds: {{first: 0, count: {seeds}}}\n"
    )
    return load_campaign(path)


def _row(e: PlannedEpisode) -> dict[str, Any]:
    return {"episode": e.key, "tree": e.tree, "seed": e.seed, "success": e.seed % 2 == 0}


class FakeEngine:
    """Stand-in engine: finishes episodes in order, optionally stops (a crash) or repeats one."""

    def __init__(self, crash_after: int | None = None, repeat: bool = False, fail_seed: int | None = None) -> None:
        self.crash_after, self.repeat, self.fail_seed = crash_after, repeat, fail_seed
        self.ran: list[int] = []

    def run(self, episodes: Sequence[PlannedEpisode]) -> Iterator[dict[str, Any] | EpisodeError]:
        for i, e in enumerate(episodes):
            if self.crash_after is not None and i == self.crash_after:
                raise KeyboardInterrupt  # Ctrl-C half-way
            self.ran.append(e.seed)
            if e.seed == self.fail_seed:
                yield EpisodeError(e, "worker lost", worker_lost=True)
                continue
            yield _row(e)
            if self.repeat:
                yield _row(e)


def test_interrupted_campaign_resumes_without_redoing_or_duplicating(tmp_path: Path) -> None:
    campaign = _campaign(tmp_path)
    first = FakeEngine(crash_after=2)
    with pytest.raises(KeyboardInterrupt):
        run_campaign(campaign, tmp_path / "out", lambda: first)
    assert [r["seed"] for r in read_rows(tmp_path / "out/c.jsonl")] == [0, 1]
    second = FakeEngine(repeat=True)
    progress = run_campaign(campaign, tmp_path / "out", lambda: second)
    assert second.ran == [2, 3, 4], "finished episodes are not run again"
    rows = read_rows(tmp_path / "out/c.jsonl")
    assert [r["seed"] for r in rows] == [0, 1, 2, 3, 4], "each episode exactly once"
    assert progress.already == 2 and progress.done == 3 and progress.successes == 3


def test_torn_last_row_is_cut_and_its_episode_runs_again(tmp_path: Path) -> None:
    campaign = _campaign(tmp_path, seeds=3)
    run_campaign(campaign, tmp_path / "out", FakeEngine)
    path = tmp_path / "out/c.jsonl"
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("".join(lines[:2]) + lines[2][:17])  # the process died while writing the third row
    engine = FakeEngine()
    run_campaign(campaign, tmp_path / "out", lambda: engine)
    assert engine.ran == [2]
    assert [json.loads(x)["seed"] for x in path.read_text().splitlines()] == [0, 1, 2]


def test_lost_worker_leaves_a_resumable_campaign(tmp_path: Path) -> None:
    campaign = _campaign(tmp_path, seeds=4)
    with pytest.raises(CampaignIncomplete, match=r"1 episode.*did not finish.*3 of 4 rows.*resume"):
        run_campaign(campaign, tmp_path / "out", lambda: FakeEngine(fail_seed=1))
    engine = FakeEngine()
    run_campaign(campaign, tmp_path / "out", lambda: engine)
    assert engine.ran == [1]
    assert sorted(r["seed"] for r in read_rows(tmp_path / "out/c.jsonl")) == [0, 1, 2, 3]


def test_rows_of_other_inputs_are_refused(tmp_path: Path) -> None:
    campaign = _campaign(tmp_path, seeds=2)
    out = tmp_path / "out"
    out.mkdir()
    (out / "c.jsonl").write_text(json.dumps({"episode": "0123456789abcdef", "tree": "t", "seed": 9}) + "\n")
    with pytest.raises(InputError, match=r"not in .* as it is now"):
        run_campaign(campaign, out, FakeEngine)


def test_a_broken_row_in_the_middle_names_its_line(tmp_path: Path) -> None:
    path = tmp_path / "r.jsonl"
    path.write_text('{"episode": "a"}\nnot json\n{"episode": "b"}\n')
    with pytest.raises(InputError) as info:
        read_rows(path)
    assert info.value.message.startswith(f"{path}:2: not a JSON object")


def test_parquet_export_round_trips(tmp_path: Path) -> None:
    import subprocess
    import sys

    import pyarrow.parquet as pq

    rows = [
        {"episode": "a", "seed": 1, "success": True, "retries": {}, "mcap": None},
        {"episode": "b", "seed": 2, "success": False, "retries": {"Perceive": 2}, "mcap": "/x.mcap"},
    ]
    path = tmp_path / "r.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    proc = subprocess.run(
        [sys.executable, "-m", "bt_grasp.cli.main", "eval", "export", str(path), "--out", str(tmp_path / "r.parquet")],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=REPO,
    )
    assert proc.returncode == 0, proc.stderr
    table = pq.read_table(tmp_path / "r.parquet").to_pylist()
    assert [r["episode"] for r in table] == ["a", "b"]
    assert json.loads(table[1]["retries"]) == {"Perceive": 2} and table[0]["mcap"] is None
