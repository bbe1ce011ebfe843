"""bt_grasp.motion never reaches the simulator: no sapien, no bt_grasp.sim (ground truth stays in tests)."""

from __future__ import annotations

import ast
from pathlib import Path

import bt_grasp.motion

FORBIDDEN = ("sapien", "bt_grasp.sim")


def test_motion_does_not_import_the_simulator() -> None:
    root = Path(bt_grasp.motion.__file__).parent
    for path in sorted(root.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            for name in names:
                assert not any(name == f or name.startswith(f + ".") for f in FORBIDDEN), f"{path.name}: {name}"
