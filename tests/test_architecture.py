"""Ground truth is quarantined and dependencies point one way (STYLE.md: 'the shape of the house')."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "bt_grasp"

# package -> module prefixes it must never import
FORBIDDEN = {
    "perception": ("sapien", "bt_grasp.sim", "bt_grasp.behaviours", "bt_grasp.tree", "bt_grasp.cli"),
    "motion": ("sapien", "bt_grasp.sim", "bt_grasp.behaviours", "bt_grasp.tree", "bt_grasp.cli"),
    "behaviours": ("sapien", "bt_grasp.sim", "bt_grasp.cli"),
    "tree": ("sapien", "bt_grasp.sim", "bt_grasp.cli"),
    "recording": ("sapien", "bt_grasp.sim", "bt_grasp.cli"),
    "faults": ("sapien", "bt_grasp.sim", "bt_grasp.cli"),
    "episode": ("sapien", "bt_grasp.cli"),
    "campaign": ("sapien", "bt_grasp.sim", "bt_grasp.cli"),  # episodes only through bt_grasp.episode
}
LEAF_MODULES = (
    "errors", "clock", "geometry", "interfaces", "config", "scene_config", "robot_description", "colors",
    "scene_fixtures", "scene_goals", "scene_conveyor",
)


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
        elif isinstance(node, ast.Call) and getattr(node.func, "id", "") == "__import__" and node.args:
            arg = node.args[0]
            if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                names.add(arg.value)
    return names


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_package_does_not_reach_the_simulator(package: str) -> None:
    folder = PKG / package
    offenders = []
    for path in folder.rglob("*.py") if folder.exists() else []:
        if path.name == "bench.py":  # benchmarks score against the simulator's truth by design
            continue
        for name in _imports(path):
            if any(name == bad or name.startswith(bad + ".") for bad in FORBIDDEN[package]):
                offenders.append(f"{path.relative_to(PKG.parent)} imports {name}")
    assert offenders == []


def test_only_sim_imports_sapien() -> None:
    offenders = [
        str(path.relative_to(PKG.parent))
        for path in PKG.rglob("*.py")
        if "sim" not in path.relative_to(PKG).parts[:1]
        and "cli" not in path.relative_to(PKG).parts[:1]
        and any(n == "sapien" or n.startswith("sapien.") for n in _imports(path))
    ]
    assert offenders == []


def test_oracle_is_used_only_by_the_judge_and_benchmarks() -> None:
    users = sorted(
        str(path.relative_to(PKG.parent))
        for path in PKG.rglob("*.py")
        if "bt_grasp.sim.oracle" in _imports(path) and path.name != "oracle.py"
    )
    allowed_prefixes = (
        "bt_grasp/cli/",
        "bt_grasp/sim/",
        "bt_grasp/judge",
        "bt_grasp/motion/bench",
        "bt_grasp/perception/bench",
        "bt_grasp/episode/follow_bench",
    )
    assert [u for u in users if not u.startswith(allowed_prefixes)] == []


@pytest.mark.parametrize("module", LEAF_MODULES)
def test_leaf_modules_import_nothing_of_ours_but_leaves(module: str) -> None:
    names = _imports(PKG / f"{module}.py")
    ours = {n.removeprefix("bt_grasp.") for n in names if n.startswith("bt_grasp.")}
    assert ours <= set(LEAF_MODULES), ours
