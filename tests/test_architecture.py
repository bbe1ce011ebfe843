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
    "resident": ("sapien", "bt_grasp.sim", "bt_grasp.cli"),  # episodes only through bt_grasp.episode
    "tasks": ("sapien", "bt_grasp.cli"),
    # the control API sits on the tree: front ends and the episode use it, it uses neither
    "control": ("sapien", "bt_grasp.sim", "bt_grasp.cli", "bt_grasp.episode", "bt_grasp.recording"),
    "scene": ("sapien", "bt_grasp.sim", "bt_grasp.perception", "bt_grasp.motion", "bt_grasp.behaviours",
              "bt_grasp.tree", "bt_grasp.episode", "bt_grasp.cli"),
}
LEAF_MODULES = ("errors", "clock", "geometry", "interfaces", "robot_description", "defaults", "files")
#: leaf packages: every module in them imports only leaf modules and modules of the same package
LEAF_PACKAGES = ("scene", "files")


def _module_name(path: Path) -> str:
    return ".".join(path.relative_to(PKG.parent).with_suffix("").parts).removesuffix(".__init__")


def _imports(path: Path) -> set[str]:
    """Every module ``path`` imports, relative imports resolved to absolute names; for ``from X import y`` both
    ``X`` and ``X.y`` (``y`` may be a module: ``from bt_grasp.sim import oracle``)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    package = _module_name(path).split(".")
    if path.name != "__init__.py":
        package = package[:-1]
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - (node.level - 1)]
                module = ".".join([*base, node.module] if node.module else base)
            else:
                module = node.module or ""
            names.add(module)
            names.update(f"{module}.{alias.name}" for alias in node.names)
        elif isinstance(node, ast.Call) and getattr(node.func, "id", "") == "__import__" and node.args:
            arg = node.args[0]
            if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                names.add(arg.value)
    return names


def test_import_reader_resolves_relative_and_from_imports(tmp_path: Path) -> None:
    probe = PKG / "perception" / "_probe_for_architecture_test.py"
    probe.write_text("from ..sim import oracle\nfrom . import cloud\nfrom bt_grasp import sim\n")
    try:
        names = _imports(probe)
    finally:
        probe.unlink()
    assert {"bt_grasp.sim.oracle", "bt_grasp.perception.cloud", "bt_grasp.sim"} <= names


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_package_does_not_reach_the_simulator(package: str) -> None:
    folder = PKG / package
    assert folder.is_dir(), f"bt_grasp/{package}/ is gone: update FORBIDDEN with where its code went"
    offenders = []
    for path in folder.rglob("*.py"):
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
        if path.relative_to(PKG).parts[0] != "sim"
        and any(n == "sapien" or n.startswith("sapien.") for n in _imports(path))
    ]
    assert offenders == []


def test_nothing_below_the_cli_imports_it() -> None:
    offenders = [
        f"{path.relative_to(PKG.parent)} imports {name}"
        for path in PKG.rglob("*.py")
        if path.relative_to(PKG).parts[0] != "cli"
        for name in _imports(path)
        if name == "bt_grasp.cli" or name.startswith("bt_grasp.cli.")
    ]
    assert offenders == []


def test_oracle_is_used_only_by_the_judge_and_benchmarks() -> None:
    users = sorted(
        str(path.relative_to(PKG.parent))
        for path in PKG.rglob("*.py")
        if any(n == "bt_grasp.sim.oracle" or n.startswith("bt_grasp.sim.oracle.") for n in _imports(path))
        and path.name != "oracle.py"
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
    path = PKG / f"{module}.py"
    if not path.exists():  # a leaf package: its own test below
        return
    names = _imports(path)
    ours = {n.removeprefix("bt_grasp.").split(".")[0] for n in names if n.startswith("bt_grasp.")}
    assert ours <= set(LEAF_MODULES), ours


@pytest.mark.parametrize("package", LEAF_PACKAGES)
def test_leaf_packages_import_only_leaves_and_themselves(package: str) -> None:
    folder = PKG / package
    assert folder.is_dir(), f"bt_grasp/{package}/ is gone: update LEAF_PACKAGES with where its code went"
    offenders = []
    for path in sorted(folder.rglob("*.py")):
        ours = {n.removeprefix("bt_grasp.").split(".")[0] for n in _imports(path) if n.startswith("bt_grasp.")}
        offenders += [f"{path.relative_to(PKG.parent)} imports bt_grasp.{o}" for o in sorted(ours)
                      if o not in LEAF_MODULES and o != package]
    assert offenders == []


def _module_graph(folder: Path) -> dict[str, set[str]]:
    """Module -> the modules of the same package it imports (``from pkg import mod`` counts as ``pkg.mod``)."""
    modules = {_module_name(p): p for p in folder.rglob("*.py")}
    return {name: {n for n in _imports(path) if n in modules and n != name} for name, path in modules.items()}


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import circle in ``graph`` (a list of modules, first == last), or None."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return [*stack[stack.index(nxt):], nxt]
            if nxt not in state and (found := visit(nxt)):
                return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (found := visit(node)):
            return found
    return None


def test_cycle_finder_finds_a_circle() -> None:
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set(), "c": {"a", "b"}}) is None


def test_the_scene_package_has_no_import_circle() -> None:
    assert _cycle(_module_graph(PKG / "scene")) is None
