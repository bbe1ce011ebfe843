"""CLI conventions (issue 24): one error format (``bt-grasp: error: ...``, one line) on every command, usage
errors included (the prefixes differed by command: ``error:`` from main, none at all from ``tree``); shell
completion on (commands and an enum option's choices complete); ``tree convert`` refuses to overwrite."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from bt_grasp.cli.main import main

REPO = Path(__file__).resolve().parents[1]
PREFIX = "bt-grasp: error: "
MISSING = "no_such_file_for_bt_grasp"


@pytest.mark.parametrize(
    "argv",
    [
        ["tree", "validate", f"{MISSING}.xml"],
        ["tree", "show", f"{MISSING}.xml"],
        ["tree", "convert", f"{MISSING}.xml", "out.yaml"],
        ["tree", "run", "--dry", f"{MISSING}.xml"],
        ["scene", "validate", f"{MISSING}.yaml"],
        ["replay", f"{MISSING}.mcap"],
        ["run", f"{MISSING}.xml", "--scene", "scenes/tabletop.yaml"],
        ["eval", "run", f"{MISSING}.yaml"],
        ["eval", "report", f"{MISSING}.jsonl", "--out", "r.html"],
        ["eval", "export", f"{MISSING}.jsonl", "--out", "r.parquet"],
        ["tree", "validate"],  # usage errors: click's message, the same prefix
        ["eval", "run", "--workers", "many"],
        ["bench", "plan", "--no-such-option"],
        ["no-such-command"],
    ],
    ids=lambda argv: "-".join(a for a in argv if MISSING not in a)[:40],
)
def test_every_command_has_the_one_error_format(
    argv: list[str], capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.chdir(REPO)
    argv = [str(tmp_path / a) if a.startswith(("r.", "out.")) else a for a in argv]
    code = main(argv)
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert code == 2 and captured.out == "", captured
    assert len(lines) == 1 and lines[0].startswith(PREFIX), captured.err
    assert "Traceback" not in captured.err


def _complete(words: str) -> list[str]:
    env = {**os.environ, "_BT_GRASP_COMPLETE": "complete_bash", "COMP_WORDS": words,
           "COMP_CWORD": str(len(words.split()) - (0 if words.endswith(" ") else 1))}
    done = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main"], env=env, cwd=REPO, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout.split()


def test_shell_completion_is_on() -> None:
    assert _complete("bt-grasp ev") == ["eval"]
    assert _complete("bt-grasp eval run --keep-logs ") == ["failures", "all", "none"]  # a typed choice


@pytest.mark.parametrize(
    ("words", "choices", "bad"),
    [
        ("bt-grasp tree show trees/pick.xml --format ", ["text", "dot", "png", "svg"], ["--format", "jpg"]),
        ("bt-grasp calibrate --mount ", ["eye-to-hand", "eye-in-hand"], ["--mount", "wrist"]),
        ("bt-grasp eval run --keep-logs ", ["failures", "all", "none"], ["--keep-logs", "some"]),
    ],
    ids=["tree-show-format", "calibrate-mount", "eval-keep-logs"],
)
def test_fixed_sets_are_typed_choices(words: str, choices: list[str], bad: list[str],
                                      capsys: pytest.CaptureFixture[str]) -> None:
    """A fixed set of values is an enum: the shell completes it and the parser refuses what is not in it (these were
    free strings checked, or not, by each command: nothing to complete)."""
    assert _complete(words) == choices
    argv = [w for w in words.split()[1:] if not w.startswith("--")][:2] + bad
    assert main(argv + (["--out", "x.yaml"] if argv[0] == "calibrate" else [])) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"{PREFIX}Invalid value for '{bad[0]}'") and f"'{bad[1]}' is not one of" in err, err


def test_install_completion_is_offered(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    assert "--install-completion" in out and "--show-completion" in out


def test_tree_convert_refuses_to_overwrite_without_force(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    source = tmp_path / "pick.xml"
    source.write_text((REPO / "trees/pick.xml").read_text())
    target = tmp_path / "pick.yaml"
    target.write_text("# my notes\n")
    assert main(["tree", "convert", str(source), str(target)]) == 2
    assert capsys.readouterr().err == f"{PREFIX}{target}: exists; pass --force to overwrite it\n"
    assert target.read_text() == "# my notes\n"  # untouched (on main as it was: silently overwritten)
    assert main(["tree", "convert", str(source), str(target), "--force"]) == 0
    assert capsys.readouterr().out == f"wrote {target}\n" and "Sequence" in target.read_text()
    assert main(["tree", "convert", str(source), str(source), "--force"]) == 2
    assert capsys.readouterr().err == f"{PREFIX}{source}: is the input file; write the converted tree to another file\n"


def _comments_of_xml(text: str) -> list[str]:
    return [" ".join(c.split()) for c in re.findall(r"<!--(.*?)-->", text, re.S)]


def _comments_of_yaml(text: str) -> list[str]:
    """The YAML's comment lines, each XML comment's lines joined back into one."""
    found: list[str] = []
    previous = -2
    for number, line in enumerate(text.splitlines()):
        if line.lstrip().startswith("#"):
            words = line.lstrip()[1:].strip()
            if number == previous + 1 and found:
                found[-1] = f"{found[-1]} {words}".strip()
            else:
                found.append(words)
            previous = number
    return found


def test_tree_convert_keeps_xml_comments_where_they_were(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """All seven comments of pick_with_recovery.xml survive XML -> YAML and XML -> XML (none did on main as it was),
    each right before the node it stood before; both outputs load to the same tree."""
    from bt_grasp.tree.loader import read_single

    source = REPO / "trees/pick_with_recovery.xml"
    expected = _comments_of_xml(source.read_text())
    assert len(expected) == 7
    as_yaml, as_xml = tmp_path / "r.yaml", tmp_path / "r.xml"
    assert main(["tree", "convert", str(source), str(as_yaml)]) == 0
    assert main(["tree", "convert", str(source), str(as_xml)]) == 0
    capsys.readouterr()
    yaml_text, xml_text = as_yaml.read_text(), as_xml.read_text()
    assert _comments_of_yaml(yaml_text) == expected
    assert _comments_of_xml(xml_text) == expected
    lines = yaml_text.splitlines()
    first = next(i for i, line in enumerate(lines) if "planning failed for the best grasp" in line)
    assert lines[first + 1].strip() == "- Sequence:" and lines[first + 2].strip() == "name: next_candidate"
    assert re.search(r"<!-- planning failed for the best grasp[^>]*-->\s*<Sequence name=\"next_candidate\"", xml_text)
    trees = [read_single(p) for p in (source, as_yaml, as_xml)]
    assert {t.trees["Recover"].root.structure() for t in trees} == {trees[0].trees["Recover"].root.structure()}
    assert [sorted(t.trees) for t in trees] == [sorted(trees[0].trees)] * 3


def test_a_comment_before_no_node_goes_to_the_top(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    source = tmp_path / "m.xml"
    source.write_text('<root BTCPP_format="4"><!-- top --><BehaviorTree ID="M"><!-- only --><AlwaysSuccess/>'
                      "<!-- closing --></BehaviorTree></root>\n")
    target = tmp_path / "m.yaml"
    assert main(["tree", "convert", str(source), str(target)]) == 0
    capsys.readouterr()
    assert target.read_text() == "# top\n# closing\nbtcpp_format: 4\ntrees:\n  # only\n  M: AlwaysSuccess\n"


def test_tree_show_png_is_readable_and_coloured(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """pick_with_recovery.xml drew 7673 x 1065 px, grey on white, on main as it was: now left to right with a
    port a line (about 3400 x 1700), every node filled with its kind's colour, legend included."""
    import shutil

    import cv2
    import numpy as np

    from bt_grasp.tree.render import KIND_FILL

    if shutil.which("dot") is None:
        pytest.fail("Graphviz 'dot' is not installed (tools/setup_system.sh installs it)")
    out = tmp_path / "tree.png"
    assert main(["tree", "show", str(REPO / "trees/pick_with_recovery.xml"), "-f", "png", "-o", str(out)]) == 0
    capsys.readouterr()
    image = cv2.imread(str(out))
    assert image is not None
    height, width = image.shape[:2]
    assert width <= 4000 and width / height <= 2.5, (width, height)
    pixels = {tuple(int(c) for c in bgr[::-1]) for bgr in image.reshape(-1, 3)[:: 7]}
    for kind, fill in KIND_FILL.items():
        rgb = tuple(int(fill[i: i + 2], 16) for i in (1, 3, 5))
        assert rgb in pixels, f"no {kind.value} fill {fill} in the picture"
    assert np.ptp(image.reshape(-1, 3).astype(int), axis=1).max() > 40  # colour, not only greys


def test_tree_show_dot_with_statuses_fills_by_status() -> None:
    from bt_grasp.cli.tree_cmd import tree_registry
    from bt_grasp.tree.loader import load_tree
    from bt_grasp.tree.render import STATUS_FILL, to_dot

    tree = load_tree(REPO / "trees/pick.xml", tree_registry())
    dot = to_dot(tree.root, tree.main_tree, with_status=True)
    nodes = [line for line in dot.splitlines() if re.match(r"\s+n\d+ \[", line)]
    assert nodes and all(f'fillcolor="{STATUS_FILL["IDLE"]}"' in n and '\\nIDLE"' in n for n in nodes), nodes
