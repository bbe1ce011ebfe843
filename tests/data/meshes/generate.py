"""Write the small mesh and URDF files the scene tests use (run from anywhere; deterministic):

    .venv/bin/python tests/data/meshes/generate.py
"""

from __future__ import annotations

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


if __name__ == "__main__":
    main()
