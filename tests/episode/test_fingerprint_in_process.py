"""An episode's run fingerprint computed while it runs (``EpisodeRequest(fingerprint=True)``, what campaign
workers use) equals the one `replay --resim` takes from its log, with a log and without one."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_grasp.episode import EpisodeRequest, WarmWorlds, run_episode
from bt_grasp.recording.fingerprint import fingerprint_of_log
from bt_grasp.recording.reader import open_log

pytestmark = [pytest.mark.sim]

REPO = Path(__file__).resolve().parents[2]


def test_the_fingerprint_computed_in_process_is_the_logs(tmp_path: Path) -> None:
    worlds = WarmWorlds()
    # a slip fault makes the recovery tree fail a Lift, recover and pick again: failures, retries, a regrasp
    request = EpisodeRequest(tree=REPO / "trees/pick_with_recovery.xml", scene=REPO / "scenes/tabletop.yaml",
                             seed=1, inject=("slip@Lift#1:force_n=2",), fingerprint=True)
    logged = run_episode(EpisodeRequest(**{**request.__dict__, "log": tmp_path / "run.mcap"}), worlds=worlds)
    unlogged = run_episode(request, worlds=worlds)
    assert logged.retries and logged.faults_fired == 1
    from_log = fingerprint_of_log(open_log(tmp_path / "run.mcap")).digest
    assert logged.fingerprint == from_log
    assert unlogged.fingerprint == from_log
    plain = run_episode(EpisodeRequest(tree=request.tree, scene=request.scene, seed=1), worlds=worlds)
    assert plain.fingerprint is None  # not asked for: nothing computed
