"""``collision: from_visual`` (issue 46): a URDF object whose collision file is a coarse hull collides as what is
drawn instead, made convex pieces by the same cached decomposition. The part here: an L drawn as two boxes, its
collision file one box over the whole L (as an object set's hull fills a mug's cup)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_grasp.errors import ConfigError
from bt_grasp.scene import mesh_cache
from bt_grasp.scene.format import load_scene
from bt_grasp.scene.graspability import collision_hides_open_space

VISUAL_A = '<visual><origin xyz="0 -0.04 0.025"/><geometry><box size="0.10 0.02 0.05"/></geometry></visual>'
VISUAL_B = '<visual><origin xyz="-0.04 0.0125 0.025"/><geometry><box size="0.02 0.075 0.05"/></geometry></visual>'
URDF = f"""<robot name="ell">
  <link name="ell">
    <inertial><mass value="0.1"/></inertial>
    {VISUAL_A}
    {VISUAL_B}
    <collision><origin xyz="0 0 0.025"/><geometry><box size="0.10 0.10 0.05"/></geometry></collision>
  </link>
</robot>
"""
DRAWN_VOLUME_M3 = 0.10 * 0.02 * 0.05 + 0.02 * 0.075 * 0.05  # two boxes 5 mm apart: two bodies
ELL_VOLUME_M3 = 0.10 * 0.02 * 0.05 + 0.02 * 0.08 * 0.05  # the L as one body


def _scene(tmp_path: Path, extra: str) -> Path:
    (tmp_path / "ell.urdf").write_text(URDF)
    scene = tmp_path / "scene.yaml"
    scene.write_text("version: 2\nobjects:\n"
                     f"  - {{name: ell, shape: urdf, urdf: ell.urdf, pose: {{xy_m: [0.5, 0.0]}}{extra}}}\n")
    return scene


def test_from_visual_collides_as_the_drawn_mesh_in_convex_pieces_cached(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path,
) -> None:
    as_filed = load_scene(_scene(tmp_path, "")).objects[0]
    assert as_filed.geometry.volume_m3 == pytest.approx(0.10 * 0.10 * 0.05, rel=1e-6)  # the coarse box
    assert collision_hides_open_space(as_filed.name, as_filed.geometry) is not None  # loading says the two differ
    drawn = load_scene(_scene(tmp_path, ", collision: from_visual")).objects[0]
    g = drawn.geometry
    assert g.volume_m3 == pytest.approx(DRAWN_VOLUME_M3, rel=1e-6)
    np.testing.assert_allclose(g.bounds_m, as_filed.geometry.bounds_m, atol=1e-9)
    assert g.sha256 != as_filed.geometry.sha256  # never the file's collision shapes from the cache
    assert collision_hides_open_space(drawn.name, g) is None  # what collides is what the camera sees
    assert drawn.mass_or_default_kg == pytest.approx(0.1)

    def refuse(*args: object, **kwargs: object) -> list[object]:
        raise AssertionError("two convex boxes were decomposed")

    monkeypatch.setattr(mesh_cache, "decompose", refuse)
    cache = tmp_path / "cache"
    cache.mkdir(mode=0o700)
    shapes = mesh_cache.collision_shapes(g, folder=cache)
    assert shapes.source is mesh_cache.ShapeSource.PIECES and len(shapes.parts) == 2
    assert shapes.volume_m3 == pytest.approx(DRAWN_VOLUME_M3, rel=1e-6)
    assert mesh_cache.collision_shapes(g, folder=cache).from_cache


def test_a_non_convex_drawing_is_decomposed_once(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    # the L drawn as one body (an OBJ): not convex, so decomposed (CoACD stood in for: it takes seconds), then cached
    import trimesh

    outline = np.array([[-0.05, -0.05], [0.05, -0.05], [0.05, -0.03], [-0.03, -0.03], [-0.03, 0.05], [-0.05, 0.05]])
    triangles = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]])
    ell = trimesh.creation.extrude_triangulation(outline, triangles, 0.05)
    assert ell.is_watertight and ell.volume == pytest.approx(ELL_VOLUME_M3, rel=1e-6)
    ell.export(tmp_path / "ell.obj")
    calls: list[int] = []

    def decompose(vertices: object, faces: object, params: object) -> list[np.ndarray]:
        calls.append(1)
        return [np.asarray(trimesh.creation.box(bounds=b).vertices, dtype=float)
                for b in (((-0.05, -0.05, 0), (0.05, -0.03, 0.05)), ((-0.05, -0.03, 0), (-0.03, 0.05, 0.05)))]

    monkeypatch.setattr(mesh_cache, "decompose", decompose)
    scene = _scene(tmp_path, ", collision: from_visual")
    (tmp_path / "ell.urdf").write_text(URDF.replace(VISUAL_A, "").replace(
        VISUAL_B, '<visual><geometry><mesh filename="ell.obj"/></geometry></visual>'))
    g = load_scene(scene).objects[0].geometry
    assert g.volume_m3 == pytest.approx(ELL_VOLUME_M3, rel=1e-6)
    cache = tmp_path / "cache"
    cache.mkdir(mode=0o700)
    shapes = mesh_cache.collision_shapes(g, folder=cache)
    assert shapes.source is mesh_cache.ShapeSource.DECOMPOSITION and len(shapes.parts) == 2 and calls == [1]
    assert mesh_cache.collision_shapes(g, folder=cache).from_cache and calls == [1]


@pytest.mark.parametrize(("obj", "says"), [
    ("{name: m, shape: mesh, mesh: m.obj, collision: from_visual, pose: {xy_m: [0.5, 0.0]}}",
     "is for urdf objects"),
    ("{name: b, shape: box, size_m: [0.05, 0.05, 0.05], color: red, collision: from_visual, "
     "pose: {xy_m: [0.5, 0.0]}}", "is for urdf objects"),
    ("{name: u, shape: urdf, urdf: ell.urdf, collision: visual, pose: {xy_m: [0.5, 0.0]}}", "from_visual"),
])
def test_collision_is_refused_where_it_means_nothing(tmp_path: Path, obj: str, says: str) -> None:
    (tmp_path / "ell.urdf").write_text(URDF)
    scene = tmp_path / "bad.yaml"
    scene.write_text(f"version: 2\nobjects:\n  - {obj}\n")
    with pytest.raises(ConfigError) as info:
        load_scene(scene)
    assert says in str(info.value) and "\n" not in str(info.value)


@pytest.mark.sim
def test_the_simulator_collides_as_drawn(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # the body's convex shapes are the two drawn boxes, not the file's one box; it rests on the table, upright,
    # with the URDF's mass
    from bt_grasp.sim.oracle import GroundTruthOracle
    from bt_grasp.sim.world import World

    monkeypatch.setenv(mesh_cache.CACHE_ENV, str(tmp_path / "cache"))
    counts = {}
    for extra in ("", ", collision: from_visual"):
        scene = _scene(tmp_path, extra)
        world = World(load_scene(scene), seed=0, source=scene)
        oracle = GroundTruthOracle(world)
        body = oracle._body("ell")
        counts[extra] = len(body.get_collision_shapes())
        T = oracle.T_world_object("ell")
        assert abs(T[2, 3]) < 0.003 and T[2, 2] > 0.999, T
        assert body.mass == pytest.approx(0.1, rel=0.02)
    assert counts == {"": 1, ", collision: from_visual": 2}
