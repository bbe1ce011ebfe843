"""Every file of tests/data/bad_trees fails `bt-grasp tree validate` with exit code 2 and one line
``<file>:<line>: problem`` on stderr, no traceback."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from bt_grasp.errors import TreeFileError
from bt_grasp.tree import builtin_registry, load_tree

BAD = Path(__file__).resolve().parents[1] / "data" / "bad_trees"
EXPECTED: dict[str, dict[str, object]] = json.loads((BAD / "expected.json").read_text())
BT_GRASP = Path(sys.executable).with_name("bt-grasp")


def test_corpus_is_complete() -> None:
    files = sorted(p.name for p in BAD.iterdir() if p.name != "expected.json")
    assert files == sorted(EXPECTED)
    assert len(files) >= 30


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_load_error_names_file_and_line(name: str) -> None:
    expected = EXPECTED[name]
    with pytest.raises(TreeFileError) as info:
        load_tree(BAD / name, builtin_registry())
    error = info.value
    assert Path(error.source).name == expected.get("file", name)
    assert error.where == f"line {expected['line']}"
    assert str(expected["contains"]) in error.problem


def _check_one_line(name: str, code: int, stdout: str, stderr: str) -> None:
    expected = EXPECTED[name]
    assert code == 2, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    shown = str(BAD / str(expected.get("file", name)))
    assert lines[0].startswith(f"bt-grasp: error: {shown}:{expected['line']}: "), lines[0]
    assert "Traceback" not in stderr and stdout == ""


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_cli_validate_prints_one_line(name: str, capsys: pytest.CaptureFixture[str]) -> None:
    from bt_grasp.cli.main import main

    code = main(["tree", "validate", str(BAD / name)])
    out = capsys.readouterr()
    _check_one_line(name, code, out.out, out.err)


@pytest.mark.parametrize("name", ["billion_laughs.xml", "python_tag.yaml", "binary_garbage.xml", "cyclic_subtree.xml"])
def test_installed_cli_validate_prints_one_line(name: str) -> None:
    result = subprocess.run(
        [str(BT_GRASP), "tree", "validate", str(BAD / name)], capture_output=True, text=True, timeout=120, check=False
    )
    _check_one_line(name, result.returncode, result.stdout, result.stderr)
