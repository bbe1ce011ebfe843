"""The floors of the new packages (STYLE.md, 'the shape of the house'), in the manner of tests/test_architecture.py:
only bt_grasp/hardware/ imports a device library, and only inside functions (the CLI starts without it); the
hardware package reaches neither the simulator nor the tree; sensing (composition) reaches the simulator only as the
episode does, never its ground truth."""

from __future__ import annotations

import ast

from test_architecture import PKG, _imports

DEVICE_LIBRARIES = ("pyrealsense2", "rtde_control", "rtde_receive", "rtde_io", "dashboard_client", "script_client")


def _is(name: str, prefixes: tuple[str, ...]) -> bool:
    return any(name == p or name.startswith(p + ".") for p in prefixes)


def test_only_the_hardware_package_imports_device_libraries_and_only_lazily() -> None:
    offenders = []
    for path in PKG.rglob("*.py"):
        inside = path.relative_to(PKG).parts[0] == "hardware"
        tree = ast.parse(path.read_text())
        top_level = {alias.name for node in tree.body if isinstance(node, ast.Import) for alias in node.names}
        top_level |= {node.module or "" for node in tree.body if isinstance(node, ast.ImportFrom)}
        for name in _imports(path):
            if _is(name, DEVICE_LIBRARIES) and (not inside or name in top_level):
                offenders.append(f"{path.relative_to(PKG.parent)} imports {name}")
    assert offenders == []


def test_hardware_and_sensing_keep_their_floors() -> None:
    forbidden = {
        "hardware": ("sapien", "bt_grasp.sim", "bt_grasp.behaviours", "bt_grasp.tree", "bt_grasp.cli",
                     "bt_grasp.perception", "bt_grasp.motion", "bt_grasp.sensing"),
        "sensing": ("sapien", "bt_grasp.cli", "bt_grasp.sim.oracle"),
    }
    offenders = [
        f"{path.relative_to(PKG.parent)} imports {name}"
        for package, bad in forbidden.items()
        for path in (PKG / package).rglob("*.py")
        for name in _imports(path)
        if _is(name, bad)
    ]
    assert offenders == []

