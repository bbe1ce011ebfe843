"""`eval run` and calibration (issue 43, finding 4): `eval run --calibration FILE` exists (the error told users to
pass it, and it was "No such option"); a refused `eval run` leaves nothing behind (it left `OUT/NAME.campaign.yaml`);
`scene validate` reports what `run` would refuse (it said "ok" for a scene whose calibration file is missing).
Episodes run in-process on the stand-in backend (no simulator)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from bt_grasp.cli.main import main
from tests.campaign.test_eval_entry import InProcessEngine

REPO = Path(__file__).resolve().parents[2]
TREE = REPO / "trees/pick.xml"
CALIBRATION = REPO / "scenes/tabletop.calibration.yaml"
PREFIX = "bt-grasp: error: "


@pytest.fixture
def in_process(monkeypatch: pytest.MonkeyPatch) -> None:
    import bt_grasp.campaign.local as local

    monkeypatch.setattr(local, "LocalEngine", InProcessEngine)


@pytest.fixture
def uncalibrated(tmp_path: Path) -> Path:
    """The tabletop scene in a folder of one's own, naming a calibration file that is nowhere: not beside it, not on
    BT_GRASP_CALIBRATION_PATH, not among the shipped ones (the shipped scene's own name would be found there)."""
    scene = tmp_path / "mine" / "tabletop.yaml"
    scene.parent.mkdir()
    text = (REPO / "scenes/tabletop.yaml").read_text()
    assert "calibration: tabletop.calibration.yaml" in text
    scene.write_text(text.replace("calibration: tabletop.calibration.yaml", "calibration: my.calibration.yaml"))
    return scene


def _cli(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def _one_sentence(err: str) -> str:
    text = err.strip()
    assert text.startswith(PREFIX) and "\n" not in text and "Traceback" not in text, err
    return text


def test_a_refused_eval_run_leaves_nothing_and_calibration_is_an_option(
        uncalibrated: Path, tmp_path: Path, in_process: None, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    base = ["eval", "run", "--tree", str(TREE), "--scene", str(uncalibrated), "--seeds", "1", "--out", str(out),
            "--keep-logs", "none", "--no-parquet"]
    code, _, err = _cli(capsys, *base)
    sentence = _one_sentence(err)
    assert code == 2 and "my.calibration.yaml" in sentence and "--calibration FILE" in sentence, sentence
    assert not out.exists(), sorted(p.name for p in out.rglob("*"))  # no OUT/NAME.campaign.yaml, no folder
    # what the sentence says to do works
    code, stdout, err = _cli(capsys, *base, "--calibration", str(CALIBRATION))
    assert code == 0, err
    assert stdout.startswith("1 episodes, ")
    written = yaml.safe_load((out / "pick-tabletop.campaign.yaml").read_text())
    assert written["calibration"] == str(CALIBRATION.resolve())


def test_a_refused_eval_run_into_an_existing_folder_leaves_it_as_it_was(
        uncalibrated: Path, tmp_path: Path, in_process: None, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine\n")
    code, _, err = _cli(capsys, "eval", "run", "--tree", str(TREE), "--scene", str(uncalibrated), "--out", str(out))
    assert code == 2, err
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]


def test_calibration_with_a_campaign_file_is_one_sentence(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = _cli(capsys, "eval", "run", str(REPO / "campaigns/smoke.yaml"), "--calibration", str(CALIBRATION),
                        "--out", str(tmp_path / "out"))
    sentence = _one_sentence(err)
    assert code == 2 and "--calibration" in sentence and "'calibration'" in sentence, sentence
    assert not (tmp_path / "out").exists()


def test_a_campaign_whose_scene_lacks_its_calibration_says_how_to_give_one(
        uncalibrated: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    campaign = tmp_path / "c.yaml"
    campaign.write_text(f"name: c\ntrees: [{TREE}]\nscenes: [{uncalibrated}]\nseeds: [0]\n")
    code, _, err = _cli(capsys, "eval", "run", str(campaign), "--out", str(tmp_path / "out"))
    sentence = _one_sentence(err)
    assert code == 2 and "'calibration'" in sentence and "--calibration FILE" not in sentence, sentence
    assert not (tmp_path / "out").exists()


def test_scene_validate_reports_what_run_refuses(uncalibrated: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from bt_grasp.episode import EpisodeRequest, load_inputs
    from bt_grasp.errors import InputError

    with pytest.raises(InputError) as refused:
        load_inputs(EpisodeRequest(tree=TREE, scene=uncalibrated))
    code, out, err = _cli(capsys, "scene", "validate", str(uncalibrated))
    sentence = _one_sentence(err)
    assert code == 2 and out == "", out
    assert refused.value.message in sentence, (refused.value.message, sentence)
    # the shipped scene, its calibration beside it: ok
    code, out, err = _cli(capsys, "scene", "validate", str(REPO / "scenes/tabletop.yaml"))
    assert code == 0 and out.startswith(f"{REPO / 'scenes/tabletop.yaml'}: ok"), (out, err)


def test_scene_validate_notes_a_default_pick_run_refuses(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """No goal declared and no red object: `run` with no --color or --goal refuses it (the default pick is red);
    the scene file is valid, so validate says ok and notes what a run needs."""
    text = (REPO / "scenes/tabletop.yaml").read_text().replace("color: red", "color: yellow")
    text = text.replace("calibration: tabletop.calibration.yaml", f"calibration: {CALIBRATION}")
    (tmp_path / "yellow.yaml").write_text(text)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("COLUMNS", "80")
    code, out, err = _cli(capsys, "scene", "validate", "yellow.yaml")
    assert code == 0, err
    assert ": ok" in out and "--color" in out and "'red'" in out, out
    assert all(len(line) <= 80 for line in out.splitlines()), out
