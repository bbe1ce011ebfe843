"""Collision shapes: a convex mesh gets its exact hull, a non-convex one CoACD parts, cached on disk by content."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_grasp.scene import mesh_cache
from bt_grasp.scene.format import load_scene
from bt_grasp.scene.mesh_cache import CoacdParams, ShapeSource, cache_dir, collision_shapes

from .conftest import MESHES


def _geometry(name: str):  # type: ignore[no-untyped-def]
    return load_scene(MESHES / name).objects[0].geometry


@pytest.fixture()
def decompositions(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Counts calls of the decomposition (the real one runs)."""
    calls: list[int] = []
    real = mesh_cache.decompose

    def counting(*args, **kwargs):  # type: ignore[no-untyped-def]
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(mesh_cache, "decompose", counting)
    return calls


def test_the_cache_folder_follows_the_environment(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("BT_GRASP_CACHE_DIR", str(tmp_path))
    assert cache_dir() == tmp_path / "meshes"
    monkeypatch.delenv("BT_GRASP_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_dir() == tmp_path / "xdg" / "bt_grasp" / "meshes"


def test_a_convex_mesh_is_its_hull_and_never_decomposed(decompositions: list[int], tmp_path: Path) -> None:
    shapes = collision_shapes(_geometry("scene_box_mesh.yaml"), folder=tmp_path)
    assert shapes.source is ShapeSource.HULL and len(shapes.parts) == 1 and not shapes.from_cache
    assert shapes.volume_m3 == pytest.approx(0.04**3, rel=1e-6)
    assert decompositions == []


def test_a_non_convex_mesh_is_decomposed_once_then_read_from_the_cache(decompositions: list[int],
                                                                        tmp_path: Path) -> None:
    geometry = _geometry("scene_cup.yaml")
    first = collision_shapes(geometry, folder=tmp_path)
    assert first.source is ShapeSource.DECOMPOSITION and len(first.parts) >= 3 and not first.from_cache
    assert decompositions == [1]
    # the parts cover the cup's volume and not its hull's (the inside of the cup stays free)
    assert geometry.volume_m3 * 0.9 < first.volume_m3 < 0.06 * 0.06 * 0.07 * 0.7
    entries = sorted(p.name for p in tmp_path.iterdir())
    assert len(entries) == 1 and entries[0].endswith(".npz"), entries  # no temporary file left behind
    assert entries[0][:-4] == mesh_cache.cache_key(geometry, CoacdParams())  # named by content, not by a file
    second = collision_shapes(_geometry("scene_cup.yaml"), folder=tmp_path)
    assert second.from_cache and decompositions == [1]
    assert len(second.parts) == len(first.parts)
    for a, b in zip(first.parts, second.parts, strict=True):
        np.testing.assert_array_equal(a, b)


def test_the_key_changes_with_scale_and_parameters() -> None:
    g = _geometry("scene_cup.yaml")
    keys = {mesh_cache.cache_key(g, CoacdParams()), mesh_cache.cache_key(g, CoacdParams(threshold=0.1))}
    scaled = type(g)(**{**g.__dict__, "scale": (2.0, 2.0, 2.0)})
    keys.add(mesh_cache.cache_key(scaled, CoacdParams()))
    assert len(keys) == 3


def test_a_damaged_entry_is_computed_again(tmp_path: Path) -> None:
    geometry = _geometry("scene_box_mesh.yaml")
    entry = tmp_path / f"{mesh_cache.cache_key(geometry, CoacdParams())}.npz"
    entry.write_bytes(b"not an npz file")
    shapes = collision_shapes(geometry, folder=tmp_path)
    assert not shapes.from_cache and shapes.source is ShapeSource.HULL
    assert collision_shapes(geometry, folder=tmp_path).from_cache  # and the entry was replaced


def test_an_unwritable_cache_folder_is_one_sentence(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from bt_grasp.errors import InputError

    blocker = tmp_path / "file"
    blocker.write_text("")
    monkeypatch.setenv("BT_GRASP_CACHE_DIR", str(blocker))
    with pytest.raises(InputError, match="cannot be written") as info:
        collision_shapes(_geometry("scene_box_mesh.yaml"))
    assert info.value.exit_code == 2
