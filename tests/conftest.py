"""Shared fixtures. Simulator tests are marked `sim`; they build real SAPIEN worlds (lavapipe on CPU)."""

from __future__ import annotations

from pathlib import Path

import pytest

pytest_plugins = ["skip_guard"]

REPO = Path(__file__).resolve().parents[1]
SCENE = REPO / "scenes" / "tabletop.yaml"


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return REPO


@pytest.fixture(scope="session")
def tabletop_scene_path() -> Path:
    return SCENE
