"""`bt-grasp --help` and `bt-grasp tree validate` import none of the heavy libraries a run needs (issue 27: they
took 0.95 s, mostly imports no such command uses). Checked in a fresh interpreter's ``sys.modules``.

A command line that names a command imports only that command's ``bt_grasp.cli`` modules
(``bt_grasp.cli.main.COMMAND_MODULES``; importing all ten cost ~30-60 ms of every command)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import typer

from bt_grasp.cli.main import COMMAND_MODULES, build_app, modules_for

HEAVY = ("open3d", "matplotlib", "pyarrow", "ray", "foxglove", "sapien", "cv2", "pinocchio", "ompl", "scipy", "mcap",
         "textual",  # textual: only `run --interactive` draws a terminal UI
         "onnxruntime", "onnx")  # only a learned detector loads a model
ALL_COMMAND_MODULES = {f"bt_grasp.cli.{m}" for names in COMMAND_MODULES.values() for m in names}

_PROBE = """
import json, sys
from bt_grasp.cli.main import main
code = main(sys.argv[1:])
print(json.dumps({"code": code, "modules": sorted(sys.modules)}))
"""


def _run_probe(repo_root: Path, argv: list[str]) -> tuple[int, set[str]]:
    done = subprocess.run(
        [sys.executable, "-c", _PROBE, *argv], cwd=repo_root, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout.strip().splitlines()[-1])
    return report["code"], set(report["modules"])


@pytest.mark.parametrize("argv", [["--help"], ["tree", "validate", "trees/pick.xml"], ["run", "--help"],
                                  ["detector", "--help"]],
                         ids=["help", "validate", "run-help", "detector-help"])
def test_the_command_imports_no_heavy_library(repo_root: Path, argv: list[str]) -> None:
    code, modules = _run_probe(repo_root, argv)
    assert code == 0
    assert "bt_grasp" in modules  # the probe did run the command
    assert sorted(set(HEAVY) & {m.split(".")[0] for m in modules}) == []


@pytest.mark.parametrize(("argv", "command"), [(["tree", "validate", "trees/pick.xml"], "tree"),
                                               (["run", "--help"], "run"), (["bench", "--help"], "bench")],
                         ids=["validate", "run-help", "bench-help"])
def test_a_command_imports_only_its_own_cli_modules(repo_root: Path, argv: list[str], command: str) -> None:
    code, modules = _run_probe(repo_root, argv)
    assert code == 0
    own = {f"bt_grasp.cli.{m}" for m in COMMAND_MODULES[command]}
    assert own <= modules
    assert sorted((modules & ALL_COMMAND_MODULES) - own) == []


def test_help_imports_every_command_module(repo_root: Path) -> None:
    code, modules = _run_probe(repo_root, ["--help"])
    assert code == 0
    assert sorted(ALL_COMMAND_MODULES - modules) == []


def _top_level_names(app: typer.Typer) -> list[str]:
    names = [info.name for info in app.registered_groups]
    names += [info.name or (info.callback.__name__ if info.callback else "") for info in app.registered_commands]
    return sorted(str(name) for name in names)


def test_the_command_table_matches_what_the_modules_register() -> None:
    """Each command's modules register exactly that command; together they register every command (a new
    command module missing from COMMAND_MODULES would be missing from --help: this fails instead)."""
    for command, modules in COMMAND_MODULES.items():
        assert _top_level_names(build_app(modules)) == [command], command
    assert _top_level_names(build_app(modules_for([]))) == sorted(COMMAND_MODULES)
    cli = Path(__file__).resolve().parents[1] / "bt_grasp" / "cli"
    on_disk = {f"bt_grasp.cli.{p.stem}" for p in cli.glob("*_cmd.py")}
    assert sorted(on_disk - ALL_COMMAND_MODULES) == []


def test_modules_for_reads_the_first_word_only() -> None:
    assert modules_for(["tree", "validate", "x.xml"]) == ("tree_cmd",)
    assert modules_for(["--help"]) == modules_for([]) == modules_for(["tre"])
    assert modules_for(["--version", "tree"]) == modules_for([])  # an option first: everything
    assert len(modules_for([])) == len(ALL_COMMAND_MODULES)


def test_the_resident_clients_modules_load_no_episode(repo_root: Path) -> None:
    """`run --resident`'s client builds the request and hands it over: the request and the client modules load
    neither the episode (the simulator's modules, numpy) nor the control package (~0.3-0.6 s of every second
    run before issue 27's second pass)."""
    code = ("import json, sys; import bt_grasp.episode.request, bt_grasp.resident.client, bt_grasp.cli.run_cmd; "
            "print(json.dumps(sorted(sys.modules)))")
    done = subprocess.run([sys.executable, "-c", code], cwd=repo_root, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    modules = set(json.loads(done.stdout.strip().splitlines()[-1]))
    assert "bt_grasp.resident.client" in modules
    assert sorted(modules & {"bt_grasp.episode.episode", "bt_grasp.episode.worlds", "bt_grasp.control", "numpy",
                             "sapien"}) == []
