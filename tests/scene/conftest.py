from __future__ import annotations

from pathlib import Path

import pytest

MESHES = Path(__file__).resolve().parents[1] / "data" / "meshes"


@pytest.fixture(autouse=True)
def _private_mesh_cache(tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Every test here caches collision shapes in its own folder, never in the user's ~/.cache."""
    root = tmp_path_factory.mktemp("cache")
    monkeypatch.setenv("BT_GRASP_CACHE_DIR", str(root))
    return root


@pytest.fixture(autouse=True)
def _fresh_notices() -> None:
    """Each test hears the scene loader's once-per-process notices afresh."""
    from bt_grasp.scene.notices import forget_notices

    forget_notices()
