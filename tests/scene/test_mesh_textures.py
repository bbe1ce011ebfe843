"""Which files a mesh file names (materials, texture images, buffers), which are missing, and which leave its folder
(the renderer refuses a file naming a missing image, so the loader draws such a mesh in its material colour; a name
that leaves the folder is never opened)."""

from __future__ import annotations

import base64
import json
from pathlib import Path

import pytest

from bt_grasp.errors import ConfigError
from bt_grasp.scene.mesh_files import MeshFiles, read_mesh_files, renderer_copy

from .conftest import MESHES
from .test_hostile_files import _png


def _read(path: Path) -> MeshFiles:
    return read_mesh_files(path, path.read_bytes(), lambda problem: ConfigError(path, problem))


def test_an_obj_names_its_mtl_maps_with_their_options(tmp_path: Path) -> None:
    (tmp_path / "a.mtl").write_text("newmtl m\nKd 1 1 1\nmap_Kd -bm 1 -o 0 0 0 colour map.png\nbump normal.png\n")
    (tmp_path / "normal.png").write_bytes(_png(4, 4, 4))
    obj = tmp_path / "a.obj"
    obj.write_text("mtllib a.mtl\nv 0 0 0\n")
    found = _read(obj)
    assert found.textures == ["normal.png"]
    assert [name for _ref, name in found.missing] == ["colour map.png"]
    copy = dict(renderer_copy(found))
    assert copy["a.obj"] == obj.read_bytes()  # nothing to rewrite: the same bytes
    assert b"colour map.png" not in copy["a.mtl"] and b"bump normal.png" in copy["a.mtl"]


def test_a_missing_mtl_names_nothing(tmp_path: Path) -> None:
    obj = tmp_path / "a.obj"
    obj.write_text("mtllib gone.mtl\nv 0 0 0\n")
    found = _read(obj)
    assert found.textures == [] and [name for _ref, name in found.missing] == ["gone.mtl"]
    assert b"mtllib" not in dict(renderer_copy(found))["a.obj"]


def test_collada_and_gltf_images(tmp_path: Path) -> None:
    dae = tmp_path / "a.dae"
    dae.write_text('<COLLADA><library_images><image id="t" name="t"><init_from>texture_map.png</init_from>'
                   "</image></library_images><library_effects><surface><init_from>t</init_from></surface>"
                   "</library_effects></COLLADA>")
    found = _read(dae)
    assert [name for _ref, name in found.missing] == ["texture_map.png"]  # not the surface's 't'
    assert found.unstageable == ""
    gltf = tmp_path / "a.gltf"
    small = "data:image/png;base64," + base64.b64encode(_png(2, 2, 2)).decode()
    gltf.write_text(json.dumps({"images": [{"uri": small}, {"uri": "wood%20grain.jpg"}]}))
    assert [name for _ref, name in _read(gltf).missing] == ["wood grain.jpg"]
    bomb = "data:image/png;base64," + base64.b64encode(_png(30_000, 30_000)).decode()
    gltf.write_text(json.dumps({"images": [{"uri": bomb}]}))
    with pytest.raises(ConfigError, match="30000 x 30000"):
        _read(gltf)
    toy = MESHES / "ros_style" / "meshes" / "toy.dae"
    assert _read(toy).textures == [] and _read(toy).missing == []


def test_names_that_leave_the_folder_are_never_opened(tmp_path: Path) -> None:
    (tmp_path / "a.mtl").write_text("newmtl m\nmap_Kd /etc/passwd\nmap_Ks ../up.png\nmap_Ka C:\\\\t\\\\x.png\n"
                                    "map_Kd http://example.invalid/x.png\nwhatever /etc/shadow\n")
    obj = tmp_path / "a.obj"
    obj.write_text("mtllib a.mtl\nmtllib /etc/x.mtl\ncall /etc/y.obj\nv 0 0 0\n")
    found = _read(obj)
    assert sorted(ref.raw for ref in found.outside) == sorted(
        ["/etc/x.mtl", "/etc/passwd", "../up.png", "C:\\\\t\\\\x.png", "http://example.invalid/x.png"])
    copy = dict(renderer_copy(found))
    assert set(copy) == {"a.obj", "a.mtl"}
    for text in copy.values():  # the renderer's copy names nothing outside: unknown statements are left out too
        assert b"/etc" not in text and b".." not in text and b"http" not in text and b"C:" not in text


def test_a_material_file_of_any_name_is_rewritten_as_one(tmp_path: Path) -> None:
    """A material file not named .mtl is still a material file to the renderer: its names are rewritten too."""
    (tmp_path / "m.txt").write_text("newmtl m\nmap_Kd /etc/passwd\nmap_Ks ok.png\n")
    (tmp_path / "ok.png").write_bytes(_png(2, 2, 2))
    obj = tmp_path / "a.obj"
    obj.write_text("mtllib m.txt\nv 0 0 0\n")
    copy = dict(renderer_copy(_read(obj)))
    assert b"/etc" not in copy["m.txt"] and b"map_Ks ok.png" in copy["m.txt"]
