"""Which texture images a mesh file names, and which are missing (the renderer refuses a file naming a missing
image, so the loader draws such a mesh in its material colour)."""

from __future__ import annotations

import json
from pathlib import Path

from bt_grasp.scene.mesh_textures import missing_textures, texture_files

from .conftest import MESHES


def test_an_obj_names_its_mtl_maps_with_their_options(tmp_path: Path) -> None:
    (tmp_path / "a.mtl").write_text("newmtl m\nKd 1 1 1\nmap_Kd -bm 1 -o 0 0 0 colour map.png\nbump normal.png\n")
    (tmp_path / "normal.png").write_bytes(b"")
    obj = tmp_path / "a.obj"
    obj.write_text("mtllib a.mtl\nv 0 0 0\n")
    assert texture_files(obj, obj.read_bytes()) == [tmp_path / "colour map.png", tmp_path / "normal.png"]
    assert missing_textures(obj, obj.read_bytes()) == [tmp_path / "colour map.png"]


def test_a_missing_mtl_names_nothing(tmp_path: Path) -> None:
    obj = tmp_path / "a.obj"
    obj.write_text("mtllib gone.mtl\nv 0 0 0\n")
    assert texture_files(obj, obj.read_bytes()) == []


def test_collada_and_gltf_images(tmp_path: Path) -> None:
    dae = tmp_path / "a.dae"
    dae.write_text('<COLLADA><library_images><image id="t" name="t"><init_from>texture_map.png</init_from>'
                   "</image></library_images><library_effects><surface><init_from>t</init_from></surface>"
                   "</library_effects></COLLADA>")
    assert missing_textures(dae, dae.read_bytes()) == [tmp_path / "texture_map.png"]  # not the surface's 't'
    gltf = tmp_path / "a.gltf"
    gltf.write_text(json.dumps({"images": [{"uri": "data:image/png;base64,AAAA"}, {"uri": "wood%20grain.jpg"}]}))
    assert texture_files(gltf, gltf.read_bytes()) == [tmp_path / "wood grain.jpg"]
    toy = MESHES / "ros_style" / "meshes" / "toy.dae"
    assert texture_files(toy, toy.read_bytes()) == []
