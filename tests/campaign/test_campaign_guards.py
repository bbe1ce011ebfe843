"""Issue 22, items 6 and 9: one coordinator per --out, and kept-log names that never leave the log folder."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from bt_grasp.campaign.out_lock import campaign_lock
from bt_grasp.campaign.spec import PlannedEpisode
from bt_grasp.campaign.worker import log_path
from bt_grasp.episode.request import EpisodeRequest
from bt_grasp.errors import InputError

REPO = Path(__file__).resolve().parents[2]


def test_item6_a_second_coordinator_on_one_out_is_refused_while_the_first_holds_it(tmp_path: Path) -> None:
    out = tmp_path / "out"
    with campaign_lock(out), pytest.raises(InputError, match=r"another campaign .* is running with this --out"), \
            campaign_lock(out):
        pass
    with campaign_lock(out):  # released when the holder is done
        pass


def test_item6_eval_run_on_a_locked_out_exits_2_with_one_sentence_and_writes_no_row(tmp_path: Path) -> None:
    out = tmp_path / "out"
    holder = subprocess.Popen(
        [sys.executable, "-c", textwrap.dedent(f"""
            import sys, time
            from pathlib import Path
            from bt_grasp.campaign.out_lock import campaign_lock
            with campaign_lock(Path({str(out)!r})):
                print("held", flush=True)
                sys.stdin.read()
        """)],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "held"
        proc = subprocess.run(
            [sys.executable, "-m", "bt_grasp.cli.main", "eval", "run", "campaigns/smoke.yaml", "--out", str(out)],
            capture_output=True, text=True, timeout=300, cwd=REPO,
        )
    finally:
        assert holder.stdin is not None and holder.stdout is not None
        holder.stdin.close()
        holder.wait(timeout=30)
        holder.stdout.close()
    assert proc.returncode == 2, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "another campaign" in lines[0], proc.stderr
    assert "Traceback" not in proc.stderr
    assert not list(out.glob("*.jsonl"))


def test_item6_a_killed_holder_leaves_no_stale_lock(tmp_path: Path) -> None:
    out = tmp_path / "out"
    script = f"from pathlib import Path\nfrom bt_grasp.campaign.out_lock import campaign_lock\nimport os\n" \
             f"with campaign_lock(Path({str(out)!r})):\n    os.kill(os.getpid(), 9)\n"
    assert subprocess.run([sys.executable, "-c", script], timeout=60).returncode == -9
    with campaign_lock(out):
        pass


@pytest.mark.parametrize("hostile", ["../../escaped", "/abs/path", "a/../../b", "..", "x\x00y"])
def test_item9_kept_log_names_from_campaign_labels_stay_in_the_log_folder(hostile: str, tmp_path: Path) -> None:
    logs = tmp_path / "out" / "logs"
    episode = PlannedEpisode(
        campaign="c", index=0, tree=f"{hostile}/pick.xml", scene=hostile, fault_plan=hostile, params=(),
        inputs_digest="d",
        request=EpisodeRequest(tree=REPO / "trees/pick.xml", scene=REPO / "scenes/tabletop.yaml", seed=3, max_ticks=10),
    )
    path = log_path(logs, episode)
    assert path.parent == logs
    assert "/" not in path.name and "\x00" not in path.name and not path.name.startswith(".")
