"""Shared fixtures. Simulator tests are marked `sim`; they build real SAPIEN worlds (lavapipe on CPU)."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest_plugins = ["skip_guard"]

REPO = Path(__file__).resolve().parents[1]
#: folders whose tests hold wall-clock bounds against a real-time process: marked ``serial``, run alone
SERIAL_FOLDERS = ("twin",)
SCENE = REPO / "scenes" / "tabletop.yaml"


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return REPO


@pytest.fixture(scope="session")
def tabletop_scene_path() -> Path:
    return SCENE


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        if Path(str(item.path)).parent.name in SERIAL_FOLDERS:
            item.add_marker(pytest.mark.serial)
