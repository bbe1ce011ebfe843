"""`bt-grasp tree convert` keeps comments both ways (issue 24): a commented tree survives XML -> YAML -> XML with each
comment before the node it stood before, and a hand-written YAML tree's ``#`` comments reach the XML. On main as it
was XML comments reached the YAML, but YAML -> XML dropped every comment (YAML's loaders drop them)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from bt_grasp.cli.main import main
from bt_grasp.tree.loader import read_single

REPO = Path(__file__).resolve().parents[2]


def _placed(xml: str) -> list[tuple[str, str]]:
    """Each comment (whitespace normalised) with the start tag that follows it (``-`` when none does)."""
    out = []
    for match in re.finditer(r"<!--(.*?)-->", xml, re.S):
        following = re.compile(r"<\s*([A-Za-z_][\w.:-]*)([^>]*)>").search(xml, match.end())
        tag = f"{following.group(1)}{following.group(2).rstrip(' /')}" if following else "-"
        out.append((" ".join(match.group(1).split()), " ".join(tag.split())))
    return out


def _convert(capsys: pytest.CaptureFixture[str], source: Path, target: Path) -> str:
    assert main(["tree", "convert", str(source), str(target)]) == 0, capsys.readouterr().err
    capsys.readouterr()
    return target.read_text()


def test_a_commented_tree_survives_xml_yaml_xml(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    source = REPO / "trees/pick_with_recovery.xml"
    expected = _placed(source.read_text())
    assert len(expected) == 7 and expected[2] == (
        "planning failed for the best grasp: try the next-ranked candidate next time", 'Sequence name="next_candidate"')
    _convert(capsys, source, tmp_path / "r.yaml")
    back = _convert(capsys, tmp_path / "r.yaml", tmp_path / "r.xml")
    # the header comment stood before <root ...>: the first start tag after it is root's, in both
    assert _placed(back) == expected
    trees = [read_single(p) for p in (source, tmp_path / "r.xml")]
    assert trees[0].structure() == trees[1].structure()
    # and once more round: nothing is added or lost
    _convert(capsys, tmp_path / "r.xml", tmp_path / "r2.yaml")
    assert (tmp_path / "r2.yaml").read_text() == (tmp_path / "r.yaml").read_text()


HAND_WRITTEN = """\
# A pick, written by hand.
# Two lines of header.

btcpp_format: 4
main_tree_to_execute: Main   # which tree runs
trees:
  # the only tree
  Main:
    # the root: one attempt
    Sequence:
      name: pick
      children:
        # look first
        - Perceive: {color: "#red"}     # a hash in quotes is no comment

        # move:
        # approach, then grasp
        - Approach: {}
        - Grasp  # close the fingers
        # nothing follows
"""


def test_a_hand_written_yaml_trees_comments_reach_the_xml(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    source = tmp_path / "pick.yaml"
    source.write_text(HAND_WRITTEN)
    xml = _convert(capsys, source, tmp_path / "pick.xml")
    root = 'root BTCPP_format="4" main_tree_to_execute="Main"'
    assert _placed(xml) == [
        # before no node: the file's top, in the order met
        ("A pick, written by hand. Two lines of header.", root),  # two lines with no blank line between: one
        ("which tree runs", root),  # at the end of a line that starts no node
        ("the only tree", root),  # before a tree's name (XML: before <BehaviorTree>)
        ("nothing follows", root),  # closing the list
        ("the root: one attempt", 'Sequence name="pick"'),
        ("look first", 'Perceive color="#red"'),
        ("a hash in quotes is no comment", 'Perceive color="#red"'),  # ends the node's line: before that node
        ("move: approach, then grasp", "Approach"),  # a blank line before it: a comment of its own
        ("close the fingers", "Grasp"),
    ]
    assert read_single(tmp_path / "pick.xml").structure() == read_single(source).structure()
    assert "#red" not in "".join(c for c, _ in _placed(xml))  # the quoted '#' stayed a value


def test_yaml_to_yaml_keeps_the_comments_too(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    source = tmp_path / "pick.yaml"
    source.write_text(HAND_WRITTEN)
    out = _convert(capsys, source, tmp_path / "again.yml")
    assert "    # the root: one attempt\n    Sequence:\n" in out
    assert re.search(r"\n( +)# move:\n\1# approach, then grasp\n\1- Approach\n", out), out


def test_a_double_dash_in_a_yaml_comment_stays_a_well_formed_xml_comment(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    source = tmp_path / "dash.yaml"
    source.write_text("trees:\n  Main:\n    # see --help -\n    AlwaysSuccess\n")
    xml = _convert(capsys, source, tmp_path / "dash.xml")
    assert read_single(tmp_path / "dash.xml").trees["Main"].root.type_id == "AlwaysSuccess"  # it parses
    assert _placed(xml) == [("see - -help -", "AlwaysSuccess")]
