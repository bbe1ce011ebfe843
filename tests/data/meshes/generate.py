"""Write the small mesh and URDF files the scene tests use (run from anywhere; deterministic):

    .venv/bin/python tests/data/meshes/generate.py
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import trimesh

HERE = Path(__file__).resolve().parent


def _obj(path: Path, mesh: trimesh.Trimesh) -> None:
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in np.round(mesh.vertices, 6)]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.faces]
    path.write_text("\n".join(lines) + "\n")


def cup() -> trimesh.Trimesh:
    """A mug-like open cup, 6 x 6 x 7 cm, walls 6 mm, floor 8 mm; origin at the bottom centre (non-convex)."""
    outer = trimesh.creation.box((0.06, 0.06, 0.07))
    inner = trimesh.creation.box((0.048, 0.048, 0.07))
    inner.apply_translation((0.0, 0.0, 0.008))
    body = trimesh.boolean.difference([outer, inner], engine="manifold")
    body.apply_translation((0.0, 0.0, 0.035))
    return body


def l_shape() -> trimesh.Trimesh:
    """An L bracket, 8 x 6 cm footprint, 2 cm thick, lying flat; origin at its bounding box's centre."""
    a = trimesh.creation.box((0.08, 0.02, 0.02))
    a.apply_translation((0.0, -0.02, 0.0))
    b = trimesh.creation.box((0.02, 0.06, 0.02))
    b.apply_translation((-0.03, 0.0, 0.0))
    return trimesh.boolean.union([a, b], engine="manifold")


def _box(lo: tuple[float, float, float], hi: tuple[float, float, float]) -> trimesh.Trimesh:
    return trimesh.creation.box(bounds=np.array([lo, hi]))


def _obj_with_uv_normals(path: Path, pieces: list[tuple[str, trimesh.Trimesh]], mtllib: str | None) -> None:
    """An OBJ as scanners and Blender write them: ``o`` groups, ``v/vt/vn`` face indices (every corner its own
    texture and normal index, so a reader that keeps them apart sees unconnected triangles)."""
    lines = [f"mtllib {mtllib}"] if mtllib else []
    base = 0
    corner = 0
    for name, mesh in pieces:
        lines.append(f"o {name}")
        lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in np.round(mesh.vertices, 6)]
        for normal in mesh.face_normals:
            lines += [f"vt {0.1 * (k + 1):.1f} {0.05 * (k + 1):.2f}" for k in range(3)]
            lines += [f"vn {normal[0]:.4f} {normal[1]:.4f} {normal[2]:.4f}"] * 3
        if mtllib:
            lines.append("usemtl material_0")
        for face in mesh.faces:
            idx = [f"{base + v + 1}/{corner + k + 1}/{corner + k + 1}" for k, v in enumerate(face)]
            lines.append("f " + " ".join(idx))
            corner += 3
        base += len(mesh.vertices)
    path.write_text("\n".join(lines) + "\n")


def vhacd_style_set(folder: Path) -> None:
    """An object as pybullet's YCB sets ship it: a textured visual OBJ whose texture image is missing, a
    collision OBJ of two separate convex pieces (V-HACD output), origins turned in the URDF, <contact> tags."""
    folder.mkdir(exist_ok=True)
    arm = _box((-0.04, -0.015, 0.0), (0.04, 0.015, 0.02))
    foot = _box((0.01, 0.015, 0.0), (0.04, 0.045, 0.02))
    _obj_with_uv_normals(folder / "visual.obj", [("l_shape", trimesh.boolean.union([arm, foot], engine="manifold"))],
                         "visual.mtl")
    (folder / "visual.mtl").write_text("newmtl material_0\nKd 0.200000 0.600000 0.900000\nTr 1.000000\n"
                                       "map_Kd texture_map.png\n")
    _obj_with_uv_normals(folder / "collision_vhacd.obj", [("hull_1", arm), ("hull_2", foot)], None)


def ros_style_package(folder: Path) -> None:
    """An object as a ROS package ships it (package.xml naming 'toy_objects'): millimetre meshes named by
    package:// (a COLLADA visual, an STL handle), a 'world' link with a floating joint, two primitive
    collisions, a second link on a fixed joint, an empty frame link, a <gazebo> tag."""
    (folder / "meshes").mkdir(parents=True, exist_ok=True)
    (folder / "urdf").mkdir(exist_ok=True)
    (folder / "package.xml").write_text('<?xml version="1.0"?>\n<package format="2">\n  <name>toy_objects</name>\n'
                                        "  <version>0.0.1</version>\n</package>\n")
    body = trimesh.creation.box((40.0, 40.0, 60.0))  # millimetres, centred
    dae = trimesh.exchange.dae.export_collada(body).decode()
    dae = re.sub(r"<(created|modified)>[^<]*</", r"<\1>2026-01-01T00:00:00</", dae)  # deterministic bytes
    ids: dict[str, str] = {}
    dae = re.sub(r"[0-9a-f]{32}", lambda m: ids.setdefault(m.group(0), f"id{len(ids)}"), dae)
    (folder / "meshes" / "toy.dae").write_text(dae)
    trimesh.creation.box((20.0, 10.0, 30.0)).export(folder / "meshes" / "handle.stl")


def main() -> None:
    box = trimesh.creation.box((0.04, 0.04, 0.04))  # a convex 4 cm cube, origin at its centre
    _obj(HERE / "box.obj", box)
    box.export(HERE / "box.stl")  # binary STL
    _obj(HERE / "cup.obj", cup())
    _obj(HERE / "l_shape.obj", l_shape())
    (HERE / "empty.obj").write_text("")
    (HERE / "degenerate.obj").write_text(  # every vertex on the x axis: no area, no volume
        "v 0 0 0\nv 0.01 0 0\nv 0.02 0 0\nv 0.03 0 0\nf 1 2 3\nf 2 3 4\nf 1 3 4\n")
    (HERE / "not_a_mesh.obj").write_text("this is not a mesh: just a sentence\n")
    vhacd_style_set(HERE / "vhacd_style")
    ros_style_package(HERE / "ros_style")


if __name__ == "__main__":
    main()
