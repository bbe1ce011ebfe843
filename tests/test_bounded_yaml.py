"""Issue 22, item 3 (inputs that exhaust the machine), found by the pre-review attack: YAML nested thousands
deep was a ``RecursionError`` traceback in every YAML reader, and a few hundred bytes of aliases ("billion
laughs") hung scene, campaign and fault-plan loading. Every YAML a user gives now goes through
``bt_grasp.files.bounded_yaml``: one sentence, exit 2, at once."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from bt_grasp.files import bounded_yaml
from bt_grasp.files.bounded_yaml import MAX_VALUES, load_value, scalar_or_text

REPO = Path(__file__).resolve().parents[1]
BT = [sys.executable, "-m", "bt_grasp.cli.main"]

DEEP = "name: " + "[" * 20_000 + "]" * 20_000 + "\n"
#: 10**9 values once expanded, 600 bytes on disk
BOMB = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]\n" for i in range(1, 9)
)
CYCLE = "a: &a [1, *a]\n"


def _refused(args: list[str], fragment: str) -> None:
    t0 = time.monotonic()
    proc = subprocess.run([*BT, *args], capture_output=True, text=True, timeout=120, cwd=REPO)
    assert proc.returncode == 2, proc.stderr[-2000:]
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and fragment in lines[0] and "Traceback" not in proc.stderr, proc.stderr[-2000:]
    assert time.monotonic() - t0 < 100


@pytest.mark.parametrize(("text", "fragment"), [(DEEP, "nested too deeply"), (BOMB, "expands to more than"),
                                                (CYCLE, "refers to the collection it is in")])
@pytest.mark.parametrize("command", ["scene", "campaign", "faults", "calibration", "tree"])
def test_item3_hostile_yaml_is_one_sentence_in_every_reader(command: str, text: str, fragment: str,
                                                            tmp_path: Path) -> None:
    path = tmp_path / "hostile.yaml"
    path.write_text(text)
    pick = ["run", "trees/pick.xml", "--scene", "scenes/tabletop.yaml"]
    args = {"scene": ["scene", "validate", str(path)], "campaign": ["eval", "run", str(path)],
            "faults": [*pick, "--faults", str(path)], "calibration": [*pick, "--calibration", str(path)],
            "tree": ["tree", "validate", str(path)]}[command]
    if command == "tree" and text is BOMB:
        fragment = "aliases"  # a tree file refuses every alias, before constructing anything
    _refused(args, fragment)


def test_item3_the_graph_check_is_linear_not_exponential() -> None:
    t0 = time.monotonic()
    with pytest.raises(ValueError, match="expands to more than"):
        bounded_yaml.compose(BOMB, yaml.SafeLoader, lambda problem, line: ValueError(problem))
    assert time.monotonic() - t0 < 5
    # a legitimate file that shares one anchor a few times still loads
    node = bounded_yaml.compose("p: &p [1, 2, 3]\nq: *p\nr: *p\n", yaml.SafeLoader, lambda p, line: ValueError(p))
    assert node is not None and bounded_yaml.construct(node, yaml.SafeLoader) == {"p": [1, 2, 3], "q": [1, 2, 3],
                                                                                   "r": [1, 2, 3]}
    assert MAX_VALUES >= 100_000


@pytest.mark.parametrize(("value", "expected"), [
    ("3", 3), ("0.5", 0.5), ("true", True), ("red", "red"), ("", ""), ("[/]v$", "[/]v$"), ("[1, 2]", "[1, 2]"),
    ("null", "null"), ("[" * 50_000, "[" * 50_000), (BOMB, BOMB), ("a: &a [*a]", "a: &a [*a]"),
])
def test_item3_a_typed_value_is_a_scalar_or_the_text_never_an_exception(value: str, expected: object) -> None:
    assert scalar_or_text(value) == expected
    assert type(scalar_or_text(value)) is type(expected)


def test_item3_load_value_refuses_what_a_file_would() -> None:
    for text in ("[" * 50_000 + "]" * 50_000, BOMB, ": : :"):
        with pytest.raises(ValueError):
            load_value(text)
    assert load_value("[1, 2]") == [1, 2]


@pytest.mark.parametrize("value", ["[/]v$", "[" * 20_000, "{a: [b"])
def test_item3_set_values_that_are_not_yaml_are_text_not_a_traceback(value: str) -> None:
    from bt_grasp.episode.request import parse_assignments

    assert parse_assignments([f"k={value}"]) == {"k": value}


def test_item3_inject_values_that_are_not_yaml_are_text_not_a_traceback() -> None:
    from bt_grasp.faults.syntax import parse_inject

    entry = parse_inject("frame_drop@Perceive#1:note=" + "[" * 20_000)
    assert entry["params"]["note"] == "[" * 20_000
