"""The house's rules, executable: floors point one way, and a folder rule for each quarantine.

``docs/architecture.md`` explains them (a package per concern, dependencies one way, ground truth
quarantined). Every rule here is a folder rule: no file-name exceptions.

- **Floors**: every package (and root module) sits on a floor; it imports only from lower floors, never from
  its own floor's other packages nor upwards. So there is no circle between packages, and ``cli/`` is the top.
- **No circle inside a package** either.
- **Quarantines**: ``sapien`` only in ``sim/`` (the controller twin lives in ``sim/twin/``, inside it);
  the ground-truth oracle (``bt_grasp.sim.oracle``) only in ``sim/`` (whose judge reads it) and ``bench/``;
  device libraries (``pyrealsense2``, ur_rtde's modules) only in ``hardware/``; the Foxglove SDK only in
  ``foxglove/``; ``bench/`` only from ``cli/``.
- **The root** holds at most eight modules besides ``__init__.py``.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "bt_grasp"

#: every package and root module of bt_grasp, by floor (0 is the ground). A package imports only packages on
#: lower floors. A new package must be given a floor here (a test fails until it is).
FLOORS: dict[str, int] = {
    # leaf modules: everything may import them; they import nothing of ours but errors
    "errors": 0,
    "clock": 1, "geometry": 1, "interfaces": 1, "robot_description": 1, "defaults": 1, "seeds": 1,
    "files": 2,  # the trust boundary: bounded reads and writes of users' files
    "process": 2,  # process set-up: threads, deferred imports, environment strings, the code fingerprint
    "scene": 3, "detector": 3, "cell": 4,  # scene files and goals; the learned detector; cell files
    "perception": 4, "motion": 4, "tree": 4,  # RGB-D in, results out; planning and execution; tree engine
    "behaviours": 5, "recording": 5, "control": 5,  # robot leaves; MCAP logs; the control API
    "faults": 6, "sim": 6, "hardware": 6, "nodes": 6,  # wrappers; the simulator; real devices; the node API
    "foxglove": 7,  # the viewer front end (live server, control bridge, layouts)
    "episode": 8, "sensing": 8,  # composes one run; perception on a camera source (no motion)
    "campaign": 9, "resident": 9,  # many episodes; the warm resident process
    "bench": 10,  # developer benchmarks (may read ground truth)
    "cli": 11,  # parses and prints
}
#: third-party modules and the one folder allowed to import each
QUARANTINE: dict[str, str] = {
    "sapien": "sim",
    "pyrealsense2": "hardware",
    "rtde_control": "hardware",
    "rtde_receive": "hardware",
    "rtde_io": "hardware",
    "dashboard_client": "hardware",
    "script_client": "hardware",
    "foxglove": "foxglove",
}
#: bt_grasp modules and the folders allowed to import each
OURS_QUARANTINE: dict[str, tuple[str, ...]] = {
    "bt_grasp.sim.oracle": ("sim", "bench"),
    "bt_grasp.bench": ("bench", "cli"),
    "bt_grasp.cli": ("cli",),
}
MAX_ROOT_MODULES = 8


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


def _module_graph(folder: Path) -> dict[str, set[str]]:
    """Module -> the modules of the same package it imports. ``from pkg import mod`` counts as ``pkg.mod`` only
    (not as the package's ``__init__``) when ``pkg.mod`` is a module; imports under ``if TYPE_CHECKING:`` are
    annotations, not imports that run, and do not count."""
    modules = {_module_name(p): p for p in folder.rglob("*.py")}
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        tree = ast.parse(path.read_text(), filename=str(path))
        skip = {id(n) for block in ast.walk(tree) if isinstance(block, ast.If) and _is_type_checking(block.test)
                for stmt in block.body for n in ast.walk(stmt)}
        package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
        found: set[str] = set()
        for node in ast.walk(tree):
            if id(node) in skip:
                continue
            if isinstance(node, ast.Import):
                found.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom):
                base = package[: len(package) - (node.level - 1)] if node.level else []
                module = ".".join([*base, node.module] if node.module else base) if node.level else node.module or ""
                subs = {f"{module}.{alias.name}" for alias in node.names} & modules.keys()
                found |= subs if subs else {module}
        graph[name] = {n for n in found if n in modules and n != name}
    return graph


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


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


@pytest.mark.parametrize("package", sorted(p.name for p in PKG.iterdir() if (p / "__init__.py").exists()))
def test_no_package_has_an_import_circle(package: str) -> None:
    assert _cycle(_module_graph(PKG / package)) is None


def _folder(path: Path) -> str:
    return path.relative_to(PKG).parts[0].removesuffix(".py")


def _sources() -> list[Path]:
    return sorted(PKG.rglob("*.py"))


def _ours(name: str) -> str | None:
    """The package or root module of bt_grasp that an imported name belongs to (None: not ours)."""
    if not name.startswith("bt_grasp."):
        return None
    return name.split(".")[1]


def test_every_package_and_root_module_has_a_floor() -> None:
    present = {p.name for p in PKG.iterdir() if (p / "__init__.py").exists()}
    present |= {p.stem for p in PKG.glob("*.py") if p.name != "__init__.py"}
    assert sorted(present - FLOORS.keys()) == []


def test_floors_point_one_way() -> None:
    offenders = []
    for path in _sources():
        if path == PKG / "__init__.py":
            continue
        here = _folder(path)
        for name in _imports(path):
            there = _ours(name)
            if there is None or there == here or there not in FLOORS:
                continue
            if FLOORS[there] >= FLOORS[here]:
                offenders.append(f"{path.relative_to(PKG.parent)} (floor {FLOORS[here]}) imports {name} "
                                 f"(floor {FLOORS[there]})")
    assert offenders == []


@pytest.mark.parametrize("library", sorted(QUARANTINE))
def test_third_party_quarantine(library: str) -> None:
    allowed = QUARANTINE[library]
    offenders = sorted(
        str(path.relative_to(PKG.parent)) for path in _sources()
        if _folder(path) != allowed and any(n == library or n.startswith(library + ".") for n in _imports(path))
    )
    assert offenders == []


@pytest.mark.parametrize("module", sorted(OURS_QUARANTINE))
def test_our_quarantine(module: str) -> None:
    allowed = OURS_QUARANTINE[module]
    offenders = sorted(
        str(path.relative_to(PKG.parent)) for path in _sources()
        if _folder(path) not in allowed and any(n == module or n.startswith(module + ".") for n in _imports(path))
    )
    assert offenders == []


def test_the_root_has_a_shape() -> None:
    modules = sorted(p.name for p in PKG.glob("*.py") if p.name != "__init__.py")
    assert len(modules) <= MAX_ROOT_MODULES, modules


def test_floor_rule_catches_an_upward_import(tmp_path: Path) -> None:
    probe = PKG / "perception" / "_probe_for_architecture_test.py"
    probe.write_text("from bt_grasp.tree import loader\nfrom bt_grasp.sim import oracle\n")
    try:
        names = _imports(probe)
    finally:
        probe.unlink()
    ups = [n for n in names if _ours(n) and FLOORS[_ours(n) or ""] >= FLOORS["perception"]]
    assert "bt_grasp.tree.loader" in ups and "bt_grasp.sim.oracle" in ups


# --- imports inside functions: deliberate, and saying why ----------------------------------------------------
#: folders whose functions import what they need when they run: command modules and run composition (a command
#: line imports only its command's modules: tests/test_cli_import_cost.py), and benchmarks
COMPOSING_FOLDERS = ("cli", "bench", "episode")
#: third-party libraries that cost start-up time or memory (or are optional extras): imported where used
HEAVY = ("sapien", "open3d", "cv2", "trimesh", "matplotlib", "scipy", "torch", "torchvision", "ultralytics",
         "onnxruntime", "onnx", "ompl", "pinocchio", "coal", "ruckig", "pyarrow", "ray", "textual", "foxglove",
         "foxglove_schemas_protobuf", "mcap", "mcap_protobuf", "rich", "coacd", "manifold3d", "collada",
         "pyrealsense2", "rtde_control", "rtde_receive", "rtde_io", "dashboard_client", "script_client", "numpy",
         "py_trees", "pydantic", "yaml", "defusedxml", "zstandard", "lz4", "typer", "google")
#: the comment that marks any other deferred import, on its line or the line above: ``# deferred: <why>``
DEFERRED = "# deferred:"


def _undeclared_deferred_imports(path: Path) -> list[str]:
    text = path.read_text()
    lines = text.splitlines()
    tree = ast.parse(text, filename=str(path))
    found = []
    for fn in ast.walk(tree):
        if not isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        for node in ast.walk(fn):
            if not isinstance(node, ast.Import | ast.ImportFrom):
                continue
            module = node.names[0].name if isinstance(node, ast.Import) else (node.module or "")
            if isinstance(node, ast.ImportFrom) and node.level == 0 and module.split(".")[0] in HEAVY:
                continue
            if isinstance(node, ast.Import) and module.split(".")[0] in HEAVY:
                continue
            here = lines[node.lineno - 1]
            above = lines[node.lineno - 2] if node.lineno > 1 else ""
            if DEFERRED in here or DEFERRED in above.strip()[:len(DEFERRED)] or above.strip().startswith(DEFERRED):
                continue
            found.append(f"{path.relative_to(PKG.parent)}:{node.lineno}: {module}")
    return found


def _deferred_offenders() -> dict[str, list[str]]:
    offenders: dict[str, list[str]] = {}
    for path in _sources():
        folder = _folder(path)
        if folder in COMPOSING_FOLDERS:
            continue
        found = _undeclared_deferred_imports(path)
        if found:
            offenders.setdefault(folder, []).extend(found)
    return offenders


def test_imports_inside_functions_say_why() -> None:
    offenders = _deferred_offenders()
    assert offenders == {}, "mark each with '# deferred: <why>' (or import it at the top)"
