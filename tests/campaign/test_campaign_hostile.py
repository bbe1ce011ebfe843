"""Issue 22, items 3 and 9, found by the pre-review attack on campaign files and --out folders:

- ``name: ".."`` put the results, the lock and the kept logs beside ``out/`` instead of in ``out/..`` (the
  default --out is out/NAME);
- ``seeds: {first: 0, count: 1000000000000}`` was a MemoryError traceback (the seed list was made before the
  episode limit was checked);
- a seed past 2**63 ran, wrote a row, then the Parquet export crashed and ``eval report`` refused the campaign's
  own results;
- ``<out>/logs`` or ``<out>/NAME.jsonl`` as a symbolic link put kept logs or rows wherever the link pointed.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from bt_grasp.campaign.spec import MAX_SEED, load_campaign
from bt_grasp.errors import ConfigError, InputError

REPO = Path(__file__).resolve().parents[2]
BT = [sys.executable, "-m", "bt_grasp.cli.main"]


def _campaign(folder: Path, body: str, name: str = "c.yaml") -> Path:
    path = folder / name
    path.write_text(textwrap.dedent(f"""\
        trees: [{REPO / 'trees/pick.xml'}]
        scenes: [{REPO / 'scenes/tabletop.yaml'}]
        max_ticks: 2
    """) + textwrap.dedent(body))
    return path


@pytest.mark.parametrize("name", ["..", ".", ".hidden", "a/b", "x" * 101, "-"])
def test_item9_a_campaign_name_is_one_plain_visible_file_name(name: str, tmp_path: Path) -> None:
    if name == "-":  # a plain name that stays allowed
        assert load_campaign(_campaign(tmp_path, f"name: '{name}'\nseeds: [1]\n"), check_inputs=False).name == "-"
        return
    with pytest.raises(ConfigError, match="names its results file"):
        load_campaign(_campaign(tmp_path, f"name: '{name}'\nseeds: [1]\n"), check_inputs=False)


def test_item9_eval_run_name_dotdot_writes_nothing_beside_out(tmp_path: Path) -> None:
    (tmp_path / "out").mkdir()
    proc = subprocess.run([*BT, "eval", "run", "--tree", str(REPO / "trees/pick.xml"), "--scene",
                           str(REPO / "scenes/tabletop.yaml"), "--seeds", "1", "--name", ".."],
                          capture_output=True, text=True, timeout=240, cwd=tmp_path)
    assert proc.returncode == 2 and "--name" in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"] and not list((tmp_path / "out").iterdir())


@pytest.mark.parametrize(("seeds", "fragment"), [
    ("{first: 0, count: 1000000000000}", "less than or equal to 1000000"),
    (f"{{first: {MAX_SEED}, count: 2}}", "is over"),
    ("[100000000000000000000000000000]", "seeds must be from 0 to"),
    ("{first: 0, count: 1000000}\nblackboard: [{a: 1}, {a: 2}]", "more than the limit"),
])
def test_item3_seed_counts_and_seeds_are_bounded_before_anything_is_made(seeds: str, fragment: str,
                                                                         tmp_path: Path) -> None:
    t0 = time.monotonic()
    with pytest.raises(ConfigError, match=fragment):
        load_campaign(_campaign(tmp_path, f"name: c\nseeds: {seeds}\n"), check_inputs=False)
    assert time.monotonic() - t0 < 10


def test_item3_a_campaign_input_is_read_bounded(tmp_path: Path) -> None:
    big = tmp_path / "big.xml"
    with big.open("wb") as f:  # a sparse 20 GB file: hashing it whole took minutes
        f.truncate(20 << 30)
    body = f"name: c\nseeds: [1]\ntrees: [{big}]\n"
    path = tmp_path / "c.yaml"
    path.write_text(f"scenes: [{REPO / 'scenes/tabletop.yaml'}]\n" + body)
    t0 = time.monotonic()
    with pytest.raises(InputError, match=r"over the .*-byte limit"):
        load_campaign(path)
    assert time.monotonic() - t0 < 10


@pytest.mark.parametrize("what", ["logs", "results"])
def test_item9_a_link_in_out_is_refused_before_any_episode(what: str, tmp_path: Path) -> None:
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    if what == "logs":
        (out / "logs").symlink_to(elsewhere)
    else:
        (out / "c.jsonl").symlink_to(elsewhere / "rows.jsonl")
    campaign = _campaign(tmp_path, "name: c\nseeds: [1]\n")
    proc = subprocess.run([*BT, "eval", "run", str(campaign), "--out", str(out), "--workers", "1"],
                          capture_output=True, text=True, timeout=240, cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "symbolic link" in lines[0] and "Traceback" not in proc.stderr, proc.stderr
    assert list(elsewhere.iterdir()) == []
