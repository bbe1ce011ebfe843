"""Shared fixtures. Simulator tests are marked `sim`; they build real SAPIEN worlds (lavapipe on CPU)."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest_plugins = ["skip_guard"]

REPO = Path(__file__).resolve().parents[1]
#: folders whose tests hold wall-clock bounds against a real-time process: marked ``serial``, run alone
SERIAL_FOLDERS = ("twin",)
#: a real-cell run against a twin stops on 100 ms without controller state, as on a robot: these run alone too
SERIAL_MODULES = ("realcell/test_cell_on_twin.py", "realcell/test_cell_twins_of_their_own.py",
                  "realcell/test_twin_camera_transport.py", "realcell/test_robotiq_client.py")
SCENE = REPO / "scenes" / "tabletop.yaml"


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return REPO


@pytest.fixture(scope="session")
def tabletop_scene_path() -> Path:
    return SCENE


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        path = Path(str(item.path))
        if path.parent.name in SERIAL_FOLDERS or f"{path.parent.name}/{path.name}" in SERIAL_MODULES:
            item.add_marker(pytest.mark.serial)
