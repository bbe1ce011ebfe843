"""Campaign files are validated like every other file: exit 2, one sentence naming file and line."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from bt_grasp.campaign.spec import load_campaign
from bt_grasp.errors import ConfigError

REPO = Path(__file__).resolve().parents[2]
BAD = REPO / "tests/data/bad_campaigns"


@pytest.mark.parametrize(
    ("name", "line", "fragment"),
    [
        ("unknown_key.yaml", 5, "unknown key 'fault_plan'; did you mean 'fault_plans'?"),
        ("missing_tree.yaml", 4, "trees[1]: no such file '../../../trees/no_such_tree.xml'"),
        ("bad_tree.yaml", 3, "trees[0] (tree) does not load"),
        ("repeated_seed.yaml", 4, "repeats a seed"),
        ("bad_fault_plan.yaml", 7, "fault_plans[1] (fault plan) does not load"),
        ("negative_count.yaml", 4, "greater than or equal to 1"),
        ("goal_colour.yaml", 4, "cannot run: --color: the pick goal's colour 'purple' is not the colour of any object"),
    ],
)
def test_bad_campaign_names_file_and_line(name: str, line: int, fragment: str) -> None:
    with pytest.raises(ConfigError) as info:
        load_campaign(BAD / name)
    message = info.value.message
    assert message.startswith(f"{BAD / name}:{line}: "), message
    assert fragment in message


def test_shipped_campaigns_load_and_expand() -> None:
    smoke = load_campaign(REPO / "campaigns/smoke.yaml")
    episodes = smoke.episodes()
    assert len(episodes) == 2 * 2 * 2 * 2
    assert len({e.key for e in episodes}) == len(episodes)
    assert {e.fault_plan for e in episodes} == {"none", "frame_drop"}
    big = load_campaign(REPO / "campaigns/recovery_eval.yaml")
    assert len(big.episodes()) == 2000


def test_episode_keys_follow_file_contents(tmp_path: Path) -> None:
    """A changed input file gives new episode keys, so old rows are never taken for the new inputs."""
    tree = tmp_path / "pick.xml"
    tree.write_text((REPO / "trees/pick.xml").read_text())
    campaign = tmp_path / "c.yaml"
    campaign.write_text(f"name: c\ntrees: [pick.xml]\nscenes: [{REPO / 'scenes/tabletop.yaml'}]\nseeds: [0]\n")
    before = load_campaign(campaign).episodes()[0].key
    assert load_campaign(campaign).episodes()[0].key == before
    lift = '<Lift height="{lift_height}" target="{target}"/>'
    tree.write_text(tree.read_text().replace(lift, lift.replace("{lift_height}", "0.2")))
    assert load_campaign(campaign).episodes()[0].key != before


def test_cli_exit_2_one_line_no_results(tmp_path: Path) -> None:
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "bt_grasp.cli.main",
            "eval",
            "run",
            str(BAD / "missing_tree.yaml"),
            "--out",
            str(tmp_path / "out"),
        ],
        capture_output=True,
        text=True,
        timeout=120,
        cwd=REPO,
    )
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "missing_tree.yaml:4:" in lines[0], proc.stderr
    assert not (tmp_path / "out").exists()
