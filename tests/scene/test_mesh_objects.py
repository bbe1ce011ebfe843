"""Mesh and URDF objects in scene files: loaded, checked, bad input answered in one sentence with file:line."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from bt_grasp.cli.main import main
from bt_grasp.errors import ConfigError
from bt_grasp.scene.format import load_scene

from .conftest import MESHES

# scene file -> (the file the sentence names, its line, a fragment of the sentence)
BAD: dict[str, tuple[str, int, str]] = {
    "bad_missing.yaml": ("bad_missing.yaml", 5, "no_such_file.obj': no such file"),
    "bad_empty.yaml": ("bad_empty.yaml", 5, "is empty"),
    "bad_garbage.yaml": ("bad_garbage.yaml", 5, "holds no triangles"),
    "bad_degenerate.yaml": ("bad_degenerate.yaml", 5, "is degenerate: its vertices lie on a line or a plane"),
    "bad_huge.yaml": ("bad_huge.yaml", 6, "larger than the table"),
    "bad_tiny.yaml": ("bad_tiny.yaml", 6, "smaller than a millimetre"),
    "bad_mass.yaml": ("bad_mass.yaml", 6, "objects[0].mass_kg: Input should be greater than 0"),
    "bad_density.yaml": ("bad_density.yaml", 6, "objects[0].density_kg_m3: Input should be greater than 0"),
    "bad_joint.yaml": ("jointed.urdf", 9, "joint 'hinge' is revolute: a URDF object must be one rigid body (fixed "
                                          "joints only; articulated objects are not supported)"),
    "bad_two_bodies.yaml": ("two_bodies.urdf", 4, "has 2 separate bodies (links 'a' and 'b' are not joined by fixed"),
    "bad_capsule.yaml": ("capsule.urdf", 5, "<capsule> geometry is not supported (mesh, box, cylinder or sphere)"),
    "bad_package.yaml": ("ros_style/urdf/toy_renamed.urdf", 15, "mesh 'package://someone_elses_pkg/meshes/toy.dae': "
                         "no package 'someone_elses_pkg' found"),
    "bad_package_escape.yaml": ("ros_style/urdf/bad_escape.urdf", 15, "its path '../../box.stl' has a '..' part"),
    "bad_url.yaml": ("ros_style/urdf/bad_url.urdf", 15, "mesh filename 'http://example.invalid/toy.dae' is a URL"),
    "bad_packages_folder.yaml": ("bad_packages_folder.yaml", 2, "package 'someone_elses_pkg' is mapped to "
                                 "'no_such_folder', which is not a folder"),
    "bad_stretch_turned.yaml": ("bad_stretch_turned.yaml", 5, "a scale that differs per axis cannot stretch its "
                                "URDF's part at line 18"),
    "bad_urdf_mass.yaml": ("zero_mass.urdf", 4, "link mass is '0'; a mass must be a positive number"),
    "bad_suffix.yaml": ("bad_suffix.yaml", 3, "is not one of .obj, .stl, .ply, .glb, .gltf, .dae"),
    "bad_size_on_mesh.yaml": ("bad_size_on_mesh.yaml", 3, "size comes from its file and 'scale', not size_m"),
    "bad_no_file.yaml": ("bad_no_file.yaml", 3, "a mesh object needs 'mesh: FILE'"),
}


def test_every_bad_mesh_scene_is_covered() -> None:
    assert sorted(p.name for p in MESHES.glob("bad_*.yaml")) == sorted(BAD)


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_mesh_input_exits_2_with_file_line_and_one_sentence(name: str, capsys: pytest.CaptureFixture[str],
                                                                _private_mesh_cache: Path) -> None:
    named, line, fragment = BAD[name]
    assert main(["scene", "validate", str(MESHES / name)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith(f"bt-grasp: error: {MESHES / named}:{line}: "), err[0]
    assert fragment in err[0], err[0]
    assert not any(_private_mesh_cache.rglob("*")), "validating writes nothing, not even to the cache"


def test_a_missing_mesh_is_one_sentence_from_the_command_line_too() -> None:
    path = MESHES / "bad_missing.yaml"
    proc = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "scene", "validate", str(path)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().splitlines() == [
        f"bt-grasp: error: {path}:5: object 'thing': cannot read '{MESHES / 'no_such_file.obj'}': no such file"]


@pytest.mark.parametrize(("name", "extents_m", "rgb", "mass_kg"), [
    ("scene_box_mesh.yaml", (0.04, 0.04, 0.04), (0.85, 0.08, 0.08), 0.1),  # colour from the scene
    ("scene_stl.yaml", (0.04, 0.04, 0.04), (0.6, 0.6, 0.6), None),  # no colour anywhere; mass from density
    ("scene_urdf.yaml", (0.04, 0.04, 0.04), (0.08, 0.2, 0.85), 0.2),  # mass from the URDF's <inertial>
    ("scene_cup.yaml", (0.06, 0.06, 0.07), (0.85, 0.08, 0.08), 0.15),
])
def test_good_mesh_scenes_load_with_their_geometry(name: str, extents_m: tuple[float, float, float],
                                                    rgb: tuple[float, float, float], mass_kg: float | None) -> None:
    obj = load_scene(MESHES / name).objects[0]
    assert obj.is_mesh
    np.testing.assert_allclose(obj.size_xyz_m, extents_m, atol=1e-6)
    assert obj.height_m == pytest.approx(extents_m[2], abs=1e-6)
    assert obj.rgb == rgb
    assert obj.mass_or_default_kg == mass_kg
    assert len(obj.geometry.sha256) == 64


def test_urdf_collision_comes_from_its_collision_mesh_and_visual_from_its_visual() -> None:
    g = load_scene(MESHES / "scene_urdf.yaml").objects[0].geometry
    assert g.collision_path == (MESHES / "box.stl").resolve()
    assert g.visual_path == (MESHES / "box.obj").resolve()


def test_scale_multiplies_the_file_units(tmp_path: Path) -> None:
    text = (MESHES / "scene_box_mesh.yaml").read_text().replace("mesh: box.obj", "mesh: box.obj\n    scale: 2")
    scene = tmp_path / "scene.yaml"
    scene.write_text(text.replace("box.obj", str(MESHES / "box.obj")))
    assert load_scene(scene).objects[0].size_xyz_m == pytest.approx((0.08, 0.08, 0.08))


def test_a_mesh_object_without_a_loaded_scene_says_so() -> None:
    from bt_grasp.scene.objects import ObjectPose, SceneObject

    obj = SceneObject(name="m", shape="mesh", mesh="box.obj", pose=ObjectPose(xy_m=(0.5, 0.0)))
    with pytest.raises(ConfigError, match="read by load_scene"):
        _ = obj.height_m


def test_a_loaded_scene_pickles_to_a_worker_with_its_geometry_and_equals_itself() -> None:
    import pickle

    scene = load_scene(MESHES / "scene_cup.yaml")
    copy = pickle.loads(pickle.dumps(scene))
    assert copy == scene and copy == load_scene(MESHES / "scene_cup.yaml")
    assert copy.objects[0].geometry.sha256 == scene.objects[0].geometry.sha256
    assert copy != load_scene(MESHES / "scene_box_mesh.yaml")
