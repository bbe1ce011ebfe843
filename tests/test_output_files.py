"""Issue 22, found by the pre-review attack: files bt_grasp writes where a user says. A dangling symbolic link
or a path under /proc as `run --log` was a traceback, a FIFO hung `run --log`, `replay --report` and
`--layout-out` for ever, /dev/full and /dev/null failed only after the whole run, and `tree convert --force`
over a symbolic link overwrote the file the link pointed at. Every writer now goes through
``bt_grasp.files.output_files``: checked before the work, written whole and renamed into place, never through a link."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from bt_grasp.errors import InputError
from bt_grasp.files.output_files import (
    check_output_file,
    check_output_folder,
    open_output_stream,
    write_output_file,
)

REPO = Path(__file__).resolve().parents[1]
BT = [sys.executable, "-m", "bt_grasp.cli.main"]
LOG = REPO / "tests/data/old_logs/format1.mcap"


def _odd_paths(tmp_path: Path) -> dict[str, tuple[Path, str]]:
    """name -> (path, what the refusal says)"""
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    dangling = tmp_path / "dangling"
    dangling.symlink_to(tmp_path / "nowhere" / "x")
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    link = tmp_path / "link.yaml"
    link.symlink_to(victim)
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    return {
        "fifo": (fifo, "not a regular file"),
        "dangling_link": (dangling, "symbolic link"),
        "link_to_a_file": (link, "symbolic link"),
        "dev_full": (Path("/dev/full"), "not a regular file"),
        "dev_null": (Path("/dev/null"), "not a regular file"),
        "under_proc": (Path("/proc/self/x.out"), "cannot write"),
        "under_a_file": (a_file / "sub" / "x.out", "is not a folder"),
        "a_folder": (tmp_path, "is a folder"),
    }


ODD = ["fifo", "dangling_link", "link_to_a_file", "dev_full", "dev_null", "under_proc", "under_a_file", "a_folder"]


@pytest.mark.parametrize("name", ODD)
def test_an_odd_output_path_is_one_sentence_before_anything_is_written(name: str, tmp_path: Path) -> None:
    path, fragment = _odd_paths(tmp_path)[name]
    with pytest.raises(InputError, match=fragment):
        write_output_file(path, "data", "--out")
    assert (tmp_path / "victim.txt").read_text() == "precious\n"
    assert not list(tmp_path.glob(".*part")) and not list(tmp_path.glob(".bt_grasp-probe-*"))


def test_a_failed_write_leaves_the_old_file_and_no_part_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    target = tmp_path / "report.html"
    target.write_text("old\n")

    def full(*args: object) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", full)
    with pytest.raises(InputError, match=r"cannot write .*no space left on device"):
        write_output_file(target, "new", "--report")
    assert target.read_text() == "old\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.html"]


def test_a_written_file_has_the_usual_mode_and_replaces_the_old_one(tmp_path: Path) -> None:
    target = tmp_path / "sub" / "out.json"
    write_output_file(target, "1\n", "--out")
    write_output_file(target, b"2\n", "--out")
    assert target.read_text() == "2\n"
    mask = os.umask(0)
    os.umask(mask)
    assert target.stat().st_mode & 0o777 == 0o666 & ~mask


def test_streams_and_folders_refuse_links_and_devices(tmp_path: Path) -> None:
    paths = _odd_paths(tmp_path)
    for name in ("fifo", "dangling_link", "link_to_a_file", "dev_null"):
        with pytest.raises(InputError):
            open_output_stream(paths[name][0], "--out", append=True)
    linked_folder = tmp_path / "linked"
    linked_folder.symlink_to(tmp_path / "elsewhere")
    with pytest.raises(InputError, match="symbolic link"):
        check_output_folder(linked_folder, "--out")
    with pytest.raises(InputError, match="is a file, not a folder"):
        check_output_folder(tmp_path / "victim.txt", "--out")
    fd = open_output_stream(tmp_path / "rows.jsonl", "--out", append=True)
    os.close(fd)
    assert check_output_file(tmp_path / "new" / "file.txt", "--out") == tmp_path / "new" / "file.txt"
    assert not (tmp_path / "new").exists()  # a check creates nothing


def _one_sentence(args: list[str], fragment: str, cwd: Path, timeout_s: float = 100) -> None:
    t0 = time.monotonic()
    proc = subprocess.run([*BT, *args], capture_output=True, text=True, timeout=240, cwd=cwd)
    assert proc.returncode == 2, proc.stderr[-2000:]
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and fragment in lines[0] and "Traceback" not in proc.stderr, proc.stderr[-2000:]
    assert time.monotonic() - t0 < timeout_s


RUN = ["run", str(REPO / "trees/pick.xml"), "--scene", str(REPO / "scenes/tabletop.yaml"), "--max-ticks", "3"]


@pytest.mark.parametrize(("name", "args"), [
    ("dangling_link", [*RUN, "--log"]),
    ("fifo", [*RUN, "--log"]),
    ("dev_full", [*RUN, "--log"]),
    ("under_proc", [*RUN, "--log"]),
    ("fifo", [*RUN, "--summary-json"]),
    ("fifo", ["replay", str(LOG), "--report"]),
    ("fifo", ["replay", str(LOG), "--foxglove", "--layout-out"]),
    ("dangling_link", ["replay", str(LOG), "--report"]),
    ("dev_full", ["replay", str(LOG), "--report"]),
    ("fifo", ["eval", "report", str(REPO / "pyproject.toml"), "--out"]),  # --out is checked first
    ("link_to_a_file", ["tree", "convert", str(REPO / "trees/pick.xml"), "--force"]),
    ("link_to_a_file", ["tree", "show", str(REPO / "trees/pick.xml"), "--format", "dot", "--out"]),
])
def test_every_command_refuses_an_odd_output_path_in_one_sentence(name: str, args: list[str], tmp_path: Path) -> None:
    path, fragment = _odd_paths(tmp_path)[name]
    _one_sentence([*args, str(path)], fragment, tmp_path)
    assert (tmp_path / "victim.txt").read_text() == "precious\n", "a link's target was written"


def test_replay_prints_an_output_path_with_markup_as_it_is(tmp_path: Path) -> None:
    proc = subprocess.run([*BT, "replay", str(LOG), "--report", "[b]x[/].html"], capture_output=True, text=True,
                          timeout=240, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "wrote the run report [b]x[/].html" in proc.stdout
    assert (tmp_path / "[b]x[").is_dir()  # the path names a folder '[b]x[' and a file '].html' in it, as given


def test_a_dataset_is_never_written_over_another_one(tmp_path: Path) -> None:
    """`detector dataset --out` over a folder holding an earlier dataset of more pictures left the old pictures
    beside the new manifest: a training set silently mixed (found by the pre-review attack)."""
    from bt_grasp.sim.labelling import make_dataset

    old = tmp_path / "ds"
    (old / "images").mkdir(parents=True)
    (old / "images" / "00007.png").write_bytes(b"an earlier dataset's picture")
    t0 = time.monotonic()
    with pytest.raises(InputError, match="holds files already"):
        make_dataset([REPO / "scenes/tabletop.yaml"], 1, old, 0)
    assert time.monotonic() - t0 < 30  # refused before anything is rendered
    assert sorted(p.name for p in old.rglob("*")) == ["00007.png", "images"]


@pytest.mark.parametrize("command", ["replay_report", "resim_log", "eval_report", "eval_export", "run_log",
                                     "run_summary", "tree_show"])
def test_an_output_is_never_written_over_the_commands_own_input(command: str, tmp_path: Path) -> None:
    """Found by the pre-review attack: `replay run.mcap --report run.mcap` replaced the log with its HTML report."""
    import shutil

    log = tmp_path / "run.mcap"
    shutil.copyfile(LOG, log)
    scene = tmp_path / "scene.yaml"
    shutil.copyfile(REPO / "scenes/tabletop.yaml", scene)
    shutil.copyfile(REPO / "scenes/tabletop.calibration.yaml", tmp_path / "tabletop.calibration.yaml")
    results = tmp_path / "r.jsonl"
    results.write_text('{"episode": "e"}\n')
    tree = tmp_path / "pick.xml"
    shutil.copyfile(REPO / "trees/pick.xml", tree)
    run = ["run", str(tree), "--scene", str(scene), "--max-ticks", "1"]
    args, victim = {
        "replay_report": (["replay", str(log), "--report", str(log)], log),
        "resim_log": (["replay", str(log), "--resim", "--resim-log", str(log)], log),
        "eval_report": (["eval", "report", str(results), "--out", str(results)], results),
        "eval_export": (["eval", "export", str(results), "--out", str(results)], results),
        "run_log": ([*run, "--log", str(scene)], scene),
        "run_summary": ([*run, "--summary-json", str(tree)], tree),
        "tree_show": (["tree", "show", str(tree), "--format", "dot", "--out", str(tree)], tree),
    }[command]
    before = victim.read_bytes()
    _one_sentence(args, "is the input file", tmp_path)
    assert victim.read_bytes() == before
