"""Write one scene file per object of an object set you have on disk (a folder of URDFs, or of mesh files), each
the way docs/scenes.md ("Bringing your own object set") says to write it: the object alone on the tabletop cell,
at (0.50, 0.00) +- 6 cm, any yaw, so that `bt-grasp bench pick --scene S` measures it over seeds.

    .venv/bin/python tools/object_set_scenes.py FOLDER --out SCENES [--prefix ycb_] [--meshes]
        [--package NAME=FOLDER ...] [--mass-kg 0.1]

FOLDER is searched (sorted, recursively) for ``*.urdf`` files (``--meshes``: ``.obj/.stl/.ply/.glb/.gltf/.dae``
files, each a ``shape: mesh`` object of ``--mass-kg``). An object's name is its file's stem, or its folder's name
when the stem says nothing (``model.urdf``, ``textured.obj``), in snake case without a leading number
(``YcbMustardBottle`` -> ``mustard_bottle``, ``011_banana`` -> ``banana``). Paths in the scenes are relative to
SCENES. ``--package NAME=FOLDER`` maps a ``package://NAME/`` the URDFs name to a folder (the scene key
``packages:``). Nothing is downloaded and nothing is written outside SCENES; an existing scene file is left as
it is unless ``--force``. Then, per scene: ``bt-grasp scene validate``, ``bt-grasp scene render``,
``bt-grasp run trees/pick_with_recovery.xml --scene S --seed N --calibration scenes/tabletop.calibration.yaml``.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path

MESH_SUFFIXES = (".obj", ".stl", ".ply", ".glb", ".gltf", ".dae")
#: file stems that name no object (the folder names it)
GENERIC_STEMS = {"model", "textured", "textured_simple", "textured_simple_reoriented", "textured_reoriented",
                 "nontextured", "mesh", "object", "visual", "collision"}


def object_name(path: Path) -> str:
    stem = path.stem if path.stem.lower() not in GENERIC_STEMS else path.parent.name
    if stem.lower() in {"google_16k", "google_64k", "tsdf", "poisson"}:  # YCB's own layout: NAME/google_16k/
        stem = path.parent.parent.name
    stem = re.sub(r"^Ycb", "", stem)
    stem = re.sub(r"([a-z0-9])([A-Z])", r"\1_\2", stem).lower()
    stem = re.sub(r"^[0-9]+(-[a-z])?_", "", stem)
    stem = re.sub(r"[^a-z0-9_]+", "_", stem).strip("_")
    return stem if stem and not stem[0].isdigit() else f"object_{stem}"


def scene_text(name: str, shape: str, file: str, packages: dict[str, str], mass_kg: float | None) -> str:
    lines = ["version: 2", f"name: {name}"]
    if packages:
        lines.append("packages: {" + ", ".join(f"{k}: {v}" for k, v in sorted(packages.items())) + "}")
    lines += ["objects:", f"  - name: {name}", f"    shape: {shape}", f"    {shape}: {file}"]
    if mass_kg is not None:
        lines.append(f"    mass_kg: {mass_kg}")
    lines += ["    pose: {xy_m: [0.50, 0.0]}",
              "    randomize: {x_m: [-0.06, 0.06], y_m: [-0.06, 0.06], yaw_deg: [-180, 180]}", ""]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--prefix", default="")
    parser.add_argument("--meshes", action="store_true", help="mesh files as shape: mesh objects, not URDFs")
    parser.add_argument("--mass-kg", type=float, default=0.1, help="a mesh object's mass (--meshes)")
    parser.add_argument("--package", action="append", default=[], metavar="NAME=FOLDER")
    parser.add_argument("--force", action="store_true", help="overwrite existing scene files")
    args = parser.parse_args(argv)
    if not args.folder.is_dir():
        print(f"object_set_scenes: {args.folder} is not a folder", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    packages: dict[str, str] = {}
    for item in args.package:
        name, sep, folder = item.partition("=")
        if not sep or not Path(folder).is_dir():
            print(f"object_set_scenes: --package {item!r}: give NAME=FOLDER with an existing folder", file=sys.stderr)
            return 2
        packages[name] = os.path.relpath(Path(folder).resolve(), args.out.resolve())
    suffixes = MESH_SUFFIXES if args.meshes else (".urdf",)
    files = sorted(p for p in args.folder.rglob("*") if p.suffix.lower() in suffixes and p.is_file())
    written: dict[str, Path] = {}
    for path in files:
        name = object_name(path)
        if name in written:
            print(f"object_set_scenes: {path} and {written[name]} are both '{name}': the second is skipped",
                  file=sys.stderr)
            continue
        scene = args.out / f"{args.prefix}{name}.yaml"
        relative = os.path.relpath(path.resolve(), args.out.resolve())
        text = scene_text(name, "mesh" if args.meshes else "urdf", relative, packages,
                          args.mass_kg if args.meshes else None)
        if scene.exists() and not args.force:
            print(f"{scene}: exists, left as it is (--force to overwrite)")
        else:
            scene.write_text(text)
            print(scene)
        written[name] = path
    if not written:
        print(f"object_set_scenes: no {' or '.join(suffixes)} file under {args.folder}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
