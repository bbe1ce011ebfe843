"""One evaluation entry point (issue 24): `eval run --tree T --scene S --seeds N` with no campaign file, an
unreachable `--ray` address refused within seconds in one sentence, `eval report --out FOLDER` refused in one
sentence (it was a traceback). Episodes run in-process on the stand-in backend (no simulator)."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import pytest

from bt_grasp.campaign.spec import PlannedEpisode
from bt_grasp.campaign.worker import KeepLogs, Worker
from bt_grasp.cli.main import main

REPO = Path(__file__).resolve().parents[2]
TREE = REPO / "trees/pick.xml"
SCENE = REPO / "scenes/tabletop.yaml"
TINY = REPO / "tests/data/campaigns/tiny.yaml"
PREFIX = "bt-grasp: error: "


class InProcessEngine:
    """LocalEngine's signature, episodes run one after another in this process on the stand-in backend."""

    def __init__(self, workers: int, factory: Any, log_dir: Path, keep: KeepLogs) -> None:
        from campaign.standin import stand_in

        self.worker = Worker(stand_in, log_dir, keep)

    def run(self, episodes: Sequence[PlannedEpisode]) -> Iterator[dict[str, Any]]:
        for episode in episodes:
            yield self.worker.run(episode)


@pytest.fixture
def in_process(monkeypatch: pytest.MonkeyPatch) -> None:
    import bt_grasp.campaign.local as local

    monkeypatch.setattr(local, "LocalEngine", InProcessEngine)


def _cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_eval_run_tree_scene_seeds_needs_no_campaign_file_and_resumes(
    tmp_path: Path, in_process: None, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    args = ["eval", "run", "--tree", str(TREE), "--scene", str(SCENE), "--seeds", "4", "--first-seed", "2",
            "--out", str(out), "--keep-logs", "none", "--no-parquet"]
    code, stdout, err = _cli(capsys, *args)
    assert code == 0, err
    results = out / "pick-tabletop.jsonl"
    assert stdout.strip() == f"4 episodes, 3 succeeded (4 run now): {results}"  # the stand-in fails seeds % 3 == 0: 3
    rows = [json.loads(line) for line in results.read_text().splitlines()]
    assert sorted(r["seed"] for r in rows) == [2, 3, 4, 5]
    assert {Path(r["tree"]).name for r in rows} == {"pick.xml"} and {r["scene"] for r in rows} == {"tabletop"}
    assert (out / "pick-tabletop.campaign.yaml").is_file()  # the campaign it stood for, on record
    code, stdout, _ = _cli(capsys, *args)  # the same command again: nothing left to run
    assert code == 0 and stdout.strip() == f"4 episodes, 3 succeeded (0 run now): {results}"


@pytest.mark.parametrize(
    ("args", "sentence"),
    [
        (["--seeds", "3"], "eval run: give a campaign file, or --tree and --scene"),
        (["--tree", "trees/no_such.xml", "--scene", "scenes/tabletop.yaml"],
         "--tree: no such file 'trees/no_such.xml'"),
        ([str(TINY), "--tree", "trees/pick.xml"], "--tree: does not go with a campaign file"),
        (["--tree", "trees/pick.xml", "--scene", "scenes/tabletop.yaml", "--name", "a b"], "--name: 'a b' may hold"),
        (["--tree", "trees/pick.xml", "--scene", "scenes/tabletop.yaml", "--keep-logs", "some"],
         "Invalid value for '--keep-logs'"),
    ],
    ids=["nothing-to-run", "missing-tree", "both", "bad-name", "bad-keep-logs"],
)
def test_eval_run_bad_options_are_one_sentence(
    args: list[str], sentence: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(REPO)
    code, out, err = _cli(capsys, "eval", "run", "--out", str(tmp_path), *args)
    assert (code, out) == (2, "") and len(err.splitlines()) == 1, err
    assert err.startswith(PREFIX + sentence), err


@pytest.mark.parametrize("address", ["127.0.0.1:1", "localhost:1"])
def test_unreachable_ray_address_fails_within_seconds_in_one_sentence(tmp_path: Path, address: str) -> None:
    # on main as it was, ray.init retried for ~2 minutes printing Ray's C++ warnings: the timeout catches it
    t0 = time.monotonic()
    proc = subprocess.run(
        [sys.executable, "-m", "bt_grasp.cli.main", "eval", "run", str(TINY), "--out", str(tmp_path),
         "--ray", address],
        capture_output=True, text=True, timeout=60, cwd=REPO,
    )
    elapsed = time.monotonic() - t0
    assert proc.returncode == 2 and proc.stdout == "", proc.stderr
    assert proc.stderr.splitlines() == [
        f"{PREFIX}--ray: cannot reach the Ray cluster at '{address}' (connection refused within 3 s); is "
        "`ray start --head` running there, and the port open?"
    ]
    assert elapsed < 15
    assert not (tmp_path / "tiny.jsonl").exists()  # refused before any episode


def test_a_ray_address_that_is_not_host_port_is_one_sentence(capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = _cli(capsys, "eval", "run", str(TINY), "--ray", "head-without-port")
    assert code == 2 and err == (f"{PREFIX}--ray: expected HOST:PORT (the head's GCS port, 6379 by default), "
                                 "'auto' or 'local', got 'head-without-port'\n")


def test_eval_report_and_export_to_a_folder_are_one_sentence(
    tmp_path: Path, in_process: None, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    code, _, err = _cli(capsys, "eval", "run", "--tree", str(TREE), "--scene", str(SCENE), "--seeds", "2",
                        "--out", str(out), "--keep-logs", "none", "--no-parquet")
    assert code == 0, err
    results = out / "pick-tabletop.jsonl"
    folder = tmp_path / "reports"
    folder.mkdir()
    # on main as it was: IsADirectoryError's traceback
    code, stdout, err = _cli(capsys, "eval", "report", str(results), "--out", str(folder))
    assert (code, stdout) == (2, "")
    assert err == f"{PREFIX}--out: '{folder}' is a folder; give a file name such as {folder / 'report.html'}\n"
    code, stdout, err = _cli(capsys, "eval", "export", str(results), "--out", str(folder))
    assert (code, stdout) == (2, "")
    assert err == f"{PREFIX}--out: '{folder}' is a folder; give a file name such as {folder / 'results.parquet'}\n"
    assert list(folder.iterdir()) == []
