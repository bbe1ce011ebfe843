"""A run of a scene with mesh and URDF objects writes its log (it crashed with ``unknown shape 'mesh'``) and the
judge's view draws each object as the mesh it is: a scene entity holding a binary STL of the object's visual
file in metres, at the object's true pose, not a box. Plus the model bytes' rules without a simulator."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from bt_grasp.episode.episode import Episode
from bt_grasp.episode.request import EpisodeRequest
from bt_grasp.recording import scene_entities
from bt_grasp.recording.reader import open_log
from bt_grasp.recording.scene_entities import MAX_MODEL_BYTES, Solid, judge_update, object_model
from bt_grasp.scene.format import load_scene

ROOT = Path(__file__).resolve().parents[2]
MESHES = ROOT / "tests" / "data" / "meshes"
TICKS = 40


def _stl_triangles(data: bytes) -> np.ndarray:
    count = int.from_bytes(data[80:84], "little")
    assert len(data) == 84 + 50 * count, "a well-formed binary STL"
    facets = np.frombuffer(data, dtype=scene_entities._STL_FACET, count=count, offset=84)
    normals = facets["normal"].astype(np.float64)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-5)  # lit, not black
    return facets["vertices"].astype(np.float64)


def _mesh_scene(folder: Path) -> Path:
    path = folder / "mesh_scene.yaml"
    path.write_text(f"""version: 2
objects:
  - {{name: red_box, shape: box, size_m: [0.05, 0.05, 0.05], color: red, pose: {{xy_m: [0.45, 0.15]}}}}
  - {{name: cup, shape: mesh, mesh: {MESHES / 'cup.obj'}, color: green, pose: {{xy_m: [0.55, 0.0], yaw_deg: 30}}}}
  - {{name: part, shape: urdf, urdf: {MESHES / 'part.urdf'}, pose: {{xy_m: [0.45, -0.15]}}}}
""")
    return path


@pytest.mark.sim
def test_a_mesh_scene_run_logs_each_mesh_object_as_its_model(tmp_path: Path,
                                                             monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("BT_GRASP_CACHE_DIR", str(tmp_path / "cache"))
    scene_path = _mesh_scene(tmp_path)
    scene = load_scene(scene_path)
    log_path = tmp_path / "mesh.mcap"
    request = EpisodeRequest(tree=ROOT / "trees/pick.xml", scene=scene_path, seed=0, max_ticks=TICKS,
                             blackboard={"color": "red", "lift_height": 0.15}, log=log_path)
    episode = Episode(request)
    episode.run()
    true_pose = {name: episode.world.objects[name].get_pose() for name in ("cup", "part", "red_box")}
    log = open_log(log_path)
    updates = [m.message for m in log.iter_messages("/judge/true_objects")]
    assert len(updates) >= 2  # at the start and at the end
    last = {e.id: e for e in updates[-1].entities}
    assert set(last) == {"true/true red_box", "true/true cup", "true/true part"}
    assert len(last["true/true red_box"].cubes) == 1 and not last["true/true red_box"].models  # primitives as before
    for name, spec in (("cup", scene.object_spec("cup")), ("part", scene.object_spec("part"))):
        entity = last[f"true/true {name}"]
        assert not entity.cubes, f"{name} drawn as a box"
        (model,) = entity.models
        assert model.media_type == "model/stl" and model.override_color
        assert (model.scale.x, model.scale.y, model.scale.z) == (1.0, 1.0, 1.0)
        p = true_pose[name].p
        assert (model.pose.position.x, model.pose.position.y, model.pose.position.z) == pytest.approx(
            (p[0], p[1], p[2]), abs=1e-6)
        assert spec is not None
        triangles = _stl_triangles(model.data)
        lo, hi = triangles.reshape(-1, 3).min(axis=0), triangles.reshape(-1, 3).max(axis=0)
        np.testing.assert_allclose(lo, spec.geometry.bounds_m[0], atol=1e-6)  # metres, the object's own frame
        np.testing.assert_allclose(hi, spec.geometry.bounds_m[1], atol=1e-6)
    cup = scene.object_spec("cup")
    assert cup is not None
    assert len(_stl_triangles(last["true/true cup"].models[0].data)) == len(cup.geometry.faces)
    # the URDF's visual file (box.obj, 12 triangles) is drawn, not its collision file
    visual = trimesh.load(MESHES / "box.obj", process=False, force="mesh")
    assert len(_stl_triangles(last["true/true part"].models[0].data)) == len(visual.faces)


def test_a_model_over_the_limit_is_drawn_as_its_hull_then_its_box(monkeypatch: pytest.MonkeyPatch) -> None:
    scene = load_scene(MESHES / "scene_cup.yaml")
    geometry = scene.objects[0].geometry
    full = object_model(geometry)
    assert len(_stl_triangles(full)) == len(geometry.faces)
    object_model.cache_clear()
    hull = trimesh.Trimesh(geometry.vertices_m, geometry.faces, process=False).convex_hull
    monkeypatch.setattr(scene_entities, "MAX_MODEL_BYTES", len(full) - 1)
    assert len(_stl_triangles(object_model(geometry))) == len(hull.faces) < len(geometry.faces)
    object_model.cache_clear()
    monkeypatch.setattr(scene_entities, "MAX_MODEL_BYTES", 84 + 50 * (len(hull.faces) - 1))
    box = _stl_triangles(object_model(geometry))
    assert len(box) == 12
    np.testing.assert_allclose(box.reshape(-1, 3).min(axis=0), geometry.bounds_m[0], atol=1e-6)
    object_model.cache_clear()
    assert MAX_MODEL_BYTES == 1 << 20


def test_a_model_solid_without_bytes_is_refused_and_an_unknown_shape_still_is() -> None:
    T = np.eye(4)
    with pytest.raises(ValueError, match="no model bytes"):
        judge_update(0, [Solid("x", "model", (0.1, 0.1, 0.1), T, (1, 1, 1, 1))])
    with pytest.raises(ValueError, match="unknown shape 'torus'"):
        judge_update(0, [Solid("x", "torus", (0.1,), T, (1, 1, 1, 1))])
