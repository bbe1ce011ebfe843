"""Installed plugins (entry point group ``bt_grasp.leaves``): discovered once, registered in a fixed order before
the ``--leaves`` files, and a bad one named by its entry point and distribution (exit 2, one sentence)."""

from __future__ import annotations

from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from bt_grasp.cli.main import main
from bt_grasp.tree import plugins
from bt_grasp.tree.builtins import builtin_registry
from bt_grasp.tree.registry import NodeRegistry

from .conftest import FakeEntryPoint

PLUGIN = Path(__file__).parent / "data" / "user_nodes.py"


def test_installed_plugins_register_in_a_fixed_order_before_leaves_files(installed: list[FakeEntryPoint]) -> None:
    calls: list[tuple[str, bool]] = []

    def hook(name: str) -> Any:  # records whether the --leaves file's node was registered before it
        return lambda registry: calls.append((name, "CheckWeight" in registry))

    installed += [FakeEntryPoint("b", "pkg_b:register", hook("z-dist/b"), "z-dist"),
                  FakeEntryPoint("a", "pkg_a:register", hook("a-dist/a"), "a-dist")]
    registry = plugins.load_plugins(builtin_registry(), [str(PLUGIN)])
    assert calls == [("a-dist/a", False), ("z-dist/b", False)]
    assert "CheckWeight" in registry
    plugins.load_plugins(builtin_registry())  # a second registry reuses the discovered hooks
    assert [name for name, _ in calls] == ["a-dist/a", "z-dist/b", "a-dist/a", "z-dist/b"]


def test_an_entry_point_naming_a_module_uses_its_register(installed: list[FakeEntryPoint]) -> None:
    module = ModuleType("user_nodes")
    module.register = plugins.load_file(PLUGIN).register  # type: ignore[attr-defined]
    installed.append(FakeEntryPoint("weights", "user_nodes", module, "weigh-dist"))
    registry = plugins.load_plugins(builtin_registry())
    assert registry.origins["CheckWeight"] == (
        "entry point 'weights = user_nodes' of weigh-dist (group bt_grasp.leaves)"
    )


@pytest.mark.parametrize(
    ("target", "problem"),
    [
        (ModuleNotFoundError("No module named 'pyzbar'", name="pyzbar"),
         "import error: ModuleNotFoundError: No module named 'pyzbar'"),
        (42, "names 42, neither a register(registry) function nor a module"),
        ("dup", "bad declaration: a node named 'Sequence' is already registered by bt_grasp "
        "(to replace it, call registry.unregister('Sequence') first)"),
    ],
)
def test_a_bad_installed_plugin_is_named_with_its_distribution(
    target: Any, problem: str, installed: list[FakeEntryPoint], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    if target == "dup":
        from bt_grasp.nodes import Leaf, action

        @action(name="Sequence")
        class Mine(Leaf):
            pass

        def target(registry: NodeRegistry) -> None:
            registry.register(Mine)

    installed.append(FakeEntryPoint("scanner", "scan_pkg.nodes:register", target, "scan-pkg"))
    tree = tmp_path / "t.xml"
    tree.write_text('<root BTCPP_format="4"><BehaviorTree ID="M"><AlwaysSuccess/></BehaviorTree></root>')
    assert main(["tree", "validate", str(tree)]) == 2
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err and len(err.splitlines()) == 1
    source = "entry point 'scanner = scan_pkg.nodes:register' of scan-pkg (group bt_grasp.leaves)"
    assert err == f"bt-grasp: error: {source}: {problem}"
