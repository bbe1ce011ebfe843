"""Ground truth is quarantined: bt_grasp.perception never imports sapien, bt_grasp.sim or the oracle."""

from __future__ import annotations

import ast
from pathlib import Path

import bt_grasp.perception

FORBIDDEN = ("sapien", "bt_grasp.sim")


def test_perception_does_not_import_the_simulator() -> None:
    root = Path(bt_grasp.perception.__file__).parent
    offenders = []
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names: list[str] = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            elif isinstance(node, ast.Call) and getattr(node.func, "id", getattr(node.func, "attr", "")) in (
                "__import__", "import_module"
            ):
                names = [a.value for a in node.args if isinstance(a, ast.Constant) and isinstance(a.value, str)]
            for name in names:
                if any(name == f or name.startswith(f + ".") for f in FORBIDDEN) or "oracle" in name:
                    offenders.append(f"{path.name}: {name}")
    assert not offenders, offenders
