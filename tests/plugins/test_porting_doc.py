"""docs/porting-btcpp.md is run block by block: Nav2's tree as committed, the plugin file made of the page's
``# nav2_nodes.py`` blocks, every ``$ bt-grasp ...`` command with the output the page shows (``...`` skips lines),
the page's test file under pytest, and its package's entry point as an installed distribution would declare it."""

from __future__ import annotations

import json
import os
import re
import shlex
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from bt_grasp.errors import TreeFileError
from bt_grasp.tree import builtin_registry, load_tree
from bt_grasp.tree.plugins import load_file

REPO = Path(__file__).resolve().parents[2]
PAGE = REPO / "docs" / "porting-btcpp.md"
NAV2 = REPO / "tests" / "data" / "nav2" / "navigate_w_replanning_time.xml"
#: section 4's files: Nav2's recovery tree and TreeNodesModel, the plugin of its controls, BT.CPP's rules as recorded
RECOVERY_FILES = [NAV2.parent / name for name in ("navigate_to_pose_w_replanning_and_recovery.xml",
                                                  "nav2_tree_nodes.xml", "nav2_controls.py")]
RULES = REPO / "tests" / "tree_conformance" / "rules" / "nav2_recoveries_in_one_tick.rules.json"


def _blocks(language: str) -> list[str]:
    return re.findall(rf"^```{language}\n(.*?)^```", PAGE.read_text(), flags=re.S | re.M)


def _file(name: str) -> str:
    """The page's python blocks that start with ``# name``, joined in order, that first line left out."""
    parts = [b.split("\n", 1)[1] for b in _blocks("python") if b.startswith(f"# {name}\n")]
    assert parts, name
    return "\n\n".join(parts)


@pytest.fixture(scope="module")
def workdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("porting")
    (folder / NAV2.name).write_bytes(NAV2.read_bytes())
    for path in RECOVERY_FILES:
        (folder / path.name).write_bytes(path.read_bytes())
    (rules,) = _blocks("json")
    (folder / "nav2_rules.json").write_text(rules)
    (folder / "nav2_nodes.py").write_text(_file("nav2_nodes.py"))
    (folder / "test_nav2_nodes.py").write_text(_file("test_nav2_nodes.py"))
    (toml,) = _blocks("toml")
    project = tomllib.loads(toml)["project"]
    name, (entry_name, entry_value) = project["name"], *project["entry-points"]["bt_grasp.leaves"].items()
    package = entry_value.split(":")[0]
    site = folder / "site"  # the package as pip would install it: its module and its dist-info
    (site / package).mkdir(parents=True)
    (site / package / "__init__.py").write_text(_file("nav2_nodes.py"))
    info = site / f"{name.replace('-', '_')}-{project['version']}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: {project['version']}\n")
    (info / "entry_points.txt").write_text(f"[bt_grasp.leaves]\n{entry_name} = {entry_value}\n")
    return folder


def test_the_porting_guide_covers_plugins_controls_and_decorators() -> None:
    """Issue 38, finding 1: the guide sent porters to an old API and never said --leaves, entry points, or how to
    write a control or a decorator."""
    page = PAGE.read_text()
    for needed in ("--leaves", "bt_grasp.leaves", "@control", "@decorator", "register_simple_action",
                   "registry.register("):
        assert needed in page, needed


def test_the_tree_on_the_page_is_nav2s_file_unchanged() -> None:
    (xml,) = _blocks("xml")
    assert xml.strip() == NAV2.read_text().strip()
    assert "Apache License" in (NAV2.parent / "LICENSE-Apache-2.0").read_text()


def _commands() -> list[tuple[str, list[str]]]:
    found = []
    for block in _blocks("console"):
        lines = block.rstrip("\n").splitlines()
        starts = [i for i, line in enumerate(lines) if line.startswith("$ ")]
        for at, start in enumerate(starts):
            end = starts[at + 1] if at + 1 < len(starts) else len(lines)
            found.append((lines[start][2:], lines[start + 1:end]))
    return found


COMMANDS = _commands()


def test_the_page_has_its_commands() -> None:
    assert len(COMMANDS) == 8


def test_the_pages_rule_file_is_the_one_btcpp_ran() -> None:
    """Section 4's rules are the file the differential corpus ran through BT.CPP 4.10 (its walk recorded beside it)."""
    (rules,) = _blocks("json")
    assert json.loads(rules) == json.loads(RULES.read_text())


@pytest.mark.parametrize(("command", "expected"), COMMANDS, ids=[c for c, _ in COMMANDS])
def test_every_command_prints_what_the_page_shows(command: str, expected: list[str], workdir: Path) -> None:
    argv = shlex.split(command)
    assert argv[0] == "bt-grasp"
    env = dict(os.environ, COLUMNS="200")
    if "--plugin" in argv:  # the installed package (its dist-info on the path, as pip leaves it)
        env["PYTHONPATH"] = os.pathsep.join([str(workdir / "site"), env.get("PYTHONPATH", "")])
    done = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", *argv[1:]], cwd=workdir, env=env,
                          capture_output=True, text=True, timeout=300, check=False)
    printed = (done.stdout + done.stderr).splitlines()
    assert "Traceback" not in done.stderr
    position = 0
    for line in expected:
        if line == "...":
            continue
        assert line in printed[position:], (line, printed)
        position = printed.index(line, position) + 1
    if "..." not in expected:
        assert printed == expected


def test_the_pages_test_passes(workdir: Path) -> None:
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:dash",
                           "-p", "no:dash.testing.plugin", "-W", "error",
                           "test_nav2_nodes.py"], cwd=workdir, capture_output=True, text=True, timeout=300,
                          check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "1 passed" in done.stdout


def test_validate_names_the_nodes_one_at_a_time_in_the_order_the_page_writes_them(workdir: Path) -> None:
    """What the page says of step 2: with the nodes written so far, the next error names the next one."""
    full = builtin_registry()
    load_file(workdir / "nav2_nodes.py").register(full)
    written: list[str] = []
    for name in ("PipelineSequence", "ControllerSelector", "PlannerSelector", "RateController",
                 "ComputePathToPose", "FollowPath"):
        builtins = builtin_registry()
        registry = builtins.with_specs([*builtins.specs(), *(full[done] for done in written)])
        with pytest.raises(TreeFileError, match=f"unknown node '{name}'"):
            load_tree(workdir / NAV2.name, registry)
        written.append(name)
    assert load_tree(workdir / NAV2.name, full).main_tree == "NavigateWithReplanningTime"
