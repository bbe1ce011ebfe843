"""Generate bt_grasp's household object set (issue 28) from primitives and revolved or swept profiles.

    python tools/make_household.py            # write bt_grasp/assets/household/*.obj and objects.yaml
    python tools/make_household.py --out DIR  # write the set into DIR instead
    python tools/make_household.py --check    # regenerate into a temporary folder, compare bytes with the set

Every mesh is built watertight by construction: revolved closed profiles (``trimesh.creation.revolve``), a swept
tapered tube with capped ends, extruded triangulations, and unions of such solids through the manifold boolean
engine (``manifold3d``). Each is written as OBJ in metres, Z up, with its origin at the bottom centre (the centre
of its bounding box's footprint, on z = 0), so it rests on the table when placed at height 0.

The output is the same bytes on every run: vertices are rounded to the micrometre and written with a fixed
format, nothing depends on the clock or on the machine, and the catalogue is written by hand rather than by a
YAML emitter. Mass is density x the mesh's own volume (a mug or a bowl is a shell, so its volume is the
ceramic's); items sold full (a bottle of water, a can of soda) carry the effective density of their contents.

Sizes fit the project's gripper (``bt_grasp.robot_description.MAX_OPENING_M``, 85 mm between the pads; the grasp
synthesis keeps 10 mm of play): each catalogue entry names one top-down grasp (a point, a horizontal closing
direction and how deep the pads reach) whose material between the pads is narrower than that, and the pen-like
rod is longer than the opening. ``tests/test_household_set.py`` checks all of this on the written files.
"""

from __future__ import annotations

import argparse
import filecmp
import math
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh
from numpy.typing import NDArray

from bt_grasp.robot_description import MAX_OPENING_M
from bt_grasp.scene.colors import COLOR_NAMES as COLORS

REPO = Path(__file__).resolve().parents[1]
DEFAULT_OUT = REPO / "bt_grasp" / "assets" / "household"
CATALOGUE = "objects.yaml"
DECIMALS = 6  # metres: one micrometre


@dataclass(frozen=True)
class Material:
    """A material's density (kg/m^3; effective for a filled container) and its friction against rubber pads."""

    name: str
    density_kg_m3: float
    friction: float


CERAMIC = Material("glazed ceramic", 2300.0, 0.5)
PET_WATER = Material("PET bottle full of water", 1000.0, 0.4)
ALUMINIUM_SODA = Material("aluminium can full of soda", 900.0, 0.35)
ABS = Material("ABS plastic", 1050.0, 0.45)
STEEL = Material("steel", 7850.0, 0.4)
WOOD = Material("wood", 600.0, 0.5)
RUBBER = Material("rubber", 1100.0, 0.9)
CARDBOARD_BOX = Material("cardboard box with contents", 400.0, 0.5)
BANANA = Material("banana", 950.0, 0.6)
PEN = Material("plastic pen (hollow)", 700.0, 0.45)


@dataclass(frozen=True)
class GraspSpec:
    """Where one top-down grasp goes: the vertical plane through ``xy_m`` (object frame) containing the
    horizontal ``closing`` direction, the pads reaching ``depth_m`` below the material's top there."""

    xy_m: tuple[float, float] | Callable[[trimesh.Trimesh], tuple[float, float]]
    closing: tuple[float, float]
    depth_m: float
    note: str


@dataclass(frozen=True)
class Grasp:
    """The grasp measured on the finished mesh: pads centred on ``point_m`` (on the material's top), closing along
    ``closing``, reaching ``depth_m`` below it, with ``width_m`` of material between them."""

    point_m: tuple[float, float, float]
    closing: tuple[float, float, float]
    depth_m: float
    width_m: float
    note: str


def measure_grasp(mesh: trimesh.Trimesh, spec: GraspSpec, opening_m: float) -> Grasp:
    """Cut the mesh with the grasp's vertical plane, keep what lies between the open pads and within the pads'
    reach below the top there, and centre the grasp on it."""
    xy = spec.xy_m(mesh) if callable(spec.xy_m) else spec.xy_m
    closing = np.array([spec.closing[0], spec.closing[1], 0.0])
    origin = np.array([xy[0], xy[1], 0.0])
    lines = trimesh.intersections.mesh_plane(mesh, np.cross(closing, [0.0, 0.0, 1.0]), origin)
    points = lines.reshape(-1, 3)
    along = (points - origin) @ closing
    points, along = points[np.abs(along) <= opening_m / 2], along[np.abs(along) <= opening_m / 2]
    if len(points) == 0:
        raise RuntimeError("a grasp plane misses the object")
    top = float(points[:, 2].max())
    band = points[:, 2] >= top - spec.depth_m
    lo, hi = float(along[band].min()), float(along[band].max())
    centre = origin + closing * (lo + hi) / 2
    point = (round(float(centre[0]), DECIMALS), round(float(centre[1]), DECIMALS), round(top, DECIMALS))
    return Grasp(point, (spec.closing[0], spec.closing[1], 0.0), spec.depth_m, round(hi - lo, DECIMALS), spec.note)


@dataclass(frozen=True)
class HouseholdObject:
    name: str
    build: Callable[[], trimesh.Trimesh]
    material: Material
    color: str
    shape_class: str  # box-like, cylinder-like, elongated, flat, other
    pose: str  # how it rests on its origin: standing, lying
    grasp: GraspSpec
    description: str


# ---------------------------------------------------------------- building blocks


def _revolve(profile: list[tuple[float, float]], sections: int = 64) -> trimesh.Trimesh:
    """A solid of revolution about z from a (radius, z) profile that starts and ends on the axis."""
    return trimesh.creation.revolve(np.asarray(profile, dtype=np.float64), sections=sections)


def _union(*meshes: trimesh.Trimesh) -> trimesh.Trimesh:
    return trimesh.boolean.union(list(meshes), engine="manifold")


def _intersection(*meshes: trimesh.Trimesh) -> trimesh.Trimesh:
    return trimesh.boolean.intersection(list(meshes), engine="manifold")


def _box(extents: tuple[float, float, float], centre: tuple[float, float, float]) -> trimesh.Trimesh:
    return trimesh.creation.box(extents=extents, transform=trimesh.transformations.translation_matrix(centre))


def _prism(polygon_xz: list[tuple[float, float]], width_y: float) -> trimesh.Trimesh:
    """A convex polygon in the xz plane (counter-clockwise seen from -y) extruded symmetrically along y."""
    n = len(polygon_xz)
    tri = np.array([[0, i, i + 1] for i in range(1, n - 1)], dtype=np.int64)
    flat = trimesh.creation.extrude_triangulation(np.asarray(polygon_xz, dtype=np.float64), tri, width_y)
    # extruded along +z from the xy plane; turn the polygon's y into z and the extrusion into y
    to_xz = np.array([[1, 0, 0, 0], [0, 0, -1, width_y / 2], [0, 1, 0, 0], [0, 0, 0, 1]], dtype=np.float64)
    flat.apply_transform(to_xz)
    if flat.volume < 0:
        flat.invert()
    return flat


def _swept_tube(centre: NDArray[np.float64], radius: NDArray[np.float64], floor_z: float,
                sides: int = 32) -> trimesh.Trimesh:
    """A tube of circular section along a planar (xy) polyline, flattened below ``floor_z`` (so that it lies on a
    flat strip, not on one point of its thickest section) and capped at both ends with a centre vertex."""
    tangent = np.gradient(centre, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    normal = np.stack([-tangent[:, 1], tangent[:, 0], np.zeros(len(centre))], axis=1)  # in plane, left of the path
    up = np.array([0.0, 0.0, 1.0])
    ring: list[NDArray[np.float64]] = []
    for c, n, r in zip(centre, normal, radius, strict=True):
        for a in (2 * math.pi * k / sides for k in range(sides)):
            p = c + r * (math.cos(a) * n + math.sin(a) * up)
            p[2] = max(p[2], floor_z)
            ring.append(p)
    vertices = [*ring, centre[0], centre[-1]]
    m = len(centre)
    first, last = m * sides, m * sides + 1
    faces: list[tuple[int, int, int]] = []
    for i in range(m - 1):
        for k in range(sides):
            a, b = i * sides + k, i * sides + (k + 1) % sides
            faces += [(a, b + sides, b), (a, a + sides, b + sides)]
    for k in range(sides):
        faces.append((first, k, (k + 1) % sides))
        faces.append((last, (m - 1) * sides + (k + 1) % sides, (m - 1) * sides + k))
    mesh = trimesh.Trimesh(np.asarray(vertices), np.asarray(faces, dtype=np.int64), process=True)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


# ---------------------------------------------------------------- the objects (built about their own origin)

MUG_R, MUG_H, MUG_WALL, MUG_BASE = 0.036, 0.095, 0.004, 0.007


def mug() -> trimesh.Trimesh:
    r_in = MUG_R - MUG_WALL
    body = _revolve([(0.0, 0.0), (MUG_R - 0.003, 0.0), (MUG_R, 0.003), (MUG_R, MUG_H), (r_in, MUG_H),
                     (r_in, MUG_BASE), (0.0, MUG_BASE)])
    # the handle: a torus standing in the xz plane, centred on the wall; only its outer half is kept
    ring = trimesh.creation.torus(major_radius=0.026, minor_radius=0.0055, major_sections=48, minor_sections=16)
    ring.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, [1, 0, 0]))
    ring.apply_translation([MUG_R, 0.0, MUG_H / 2])
    keep = _box((0.05, 0.02, 0.08), (MUG_R - MUG_WALL / 2 + 0.025, 0.0, MUG_H / 2))
    return _union(body, _intersection(ring, keep))


def bowl() -> trimesh.Trimesh:
    return _revolve([(0.0, 0.0), (0.035, 0.0), (0.036, 0.008), (0.050, 0.020), (0.062, 0.040), (0.066, 0.055),
                     (0.061, 0.055), (0.057, 0.041), (0.046, 0.024), (0.034, 0.013), (0.0, 0.012)])


def bottle() -> trimesh.Trimesh:
    return _revolve([(0.0, 0.0), (0.026, 0.0), (0.029, 0.004), (0.029, 0.120), (0.024, 0.140), (0.014, 0.158),
                     (0.0125, 0.166), (0.0145, 0.167), (0.0145, 0.185), (0.013, 0.187), (0.0, 0.187)])


def can() -> trimesh.Trimesh:
    return _revolve([(0.0, 0.0), (0.026, 0.0), (0.033, 0.010), (0.033, 0.110), (0.029, 0.120), (0.029, 0.122),
                     (0.0, 0.122)])


def banana() -> trimesh.Trimesh:
    bend_radius, span = 0.13, math.radians(80.0)
    t = np.linspace(0.0, 1.0, 41)
    angle = -span / 2 + span * t
    centre = np.stack([bend_radius * np.sin(angle), -bend_radius * np.cos(angle), np.zeros_like(t)], axis=1)
    radius = 0.005 + 0.0125 * np.sin(np.pi * t) ** 0.6
    return _swept_tube(centre, radius, floor_z=-0.7 * float(radius.max()))


def t_tool() -> trimesh.Trimesh:
    stem = _box((0.130, 0.022, 0.022), (0.0, 0.0, 0.011))
    bar = _box((0.028, 0.100, 0.026), (0.079, 0.0, 0.013))
    return _union(stem, bar)


def l_bracket() -> trimesh.Trimesh:
    base = _box((0.070, 0.030, 0.004), (0.0, 0.0, 0.002))
    upright = _box((0.004, 0.030, 0.050), (-0.033, 0.0, 0.025))
    return _union(base, upright)


def wedge() -> trimesh.Trimesh:
    return _prism([(-0.045, 0.0), (0.045, 0.0), (0.045, 0.006), (-0.045, 0.035)], 0.045)


def ring() -> trimesh.Trimesh:
    return trimesh.creation.torus(major_radius=0.028, minor_radius=0.0075, major_sections=64, minor_sections=24)


def small_box() -> trimesh.Trimesh:
    return _box((0.065, 0.045, 0.030), (0.0, 0.0, 0.015))


def plate() -> trimesh.Trimesh:
    return _revolve([(0.0, 0.0), (0.050, 0.0), (0.052, 0.004), (0.075, 0.016), (0.085, 0.021), (0.085, 0.025),
                     (0.081, 0.025), (0.072, 0.019), (0.050, 0.008), (0.0, 0.008)])


def pen() -> trimesh.Trimesh:
    # a hexagonal barrel (six sections, so it does not roll) with a conical tip, lying along x on a flat face
    rod = _revolve([(0.0, 0.0), (0.007, 0.0), (0.007, 0.126), (0.0015, 0.146), (0.0, 0.146)], sections=6)
    rod.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 6, [0, 0, 1]))
    rod.apply_transform(trimesh.transformations.rotation_matrix(math.pi / 2, [0, 1, 0]))
    return rod


def _mug_axis(mesh: trimesh.Trimesh) -> tuple[float, float]:
    """The mug body's axis in the finished mesh (the handle makes it differ from the bottom centre)."""
    return (float(mesh.bounds[0][0]) + MUG_R, 0.0)


X, Y = (1.0, 0.0), (0.0, 1.0)

OBJECTS: tuple[HouseholdObject, ...] = (
    HouseholdObject("mug", mug, CERAMIC, "white", "cylinder-like", "standing",
                    GraspSpec(_mug_axis, Y, 0.03, "across the body, the handle along +x"),
                    "A 95 mm ceramic mug, hollow, with a ring handle on one side."),
    HouseholdObject("bowl", bowl, CERAMIC, "blue", "other", "standing",
                    GraspSpec((0.0635, 0.0), X, 0.02, "across the rim wall"),
                    "A 132 mm ceramic bowl, 55 mm deep-walled, flared rim."),
    HouseholdObject("bottle", bottle, PET_WATER, "green", "cylinder-like", "standing",
                    GraspSpec((0.0, 0.0), X, 0.02, "across the cap"),
                    "A 330 ml water bottle, 187 mm tall, full."),
    HouseholdObject("can", can, ALUMINIUM_SODA, "red", "cylinder-like", "standing",
                    GraspSpec((0.0, 0.0), X, 0.03, "across the body"),
                    "A 330 ml soda can, 66 mm across, 122 mm tall, full."),
    HouseholdObject("banana", banana, BANANA, "yellow", "elongated", "lying",
                    GraspSpec((0.0, 0.0), Y, 0.02, "across the tube at its middle"),
                    "A banana-like curved tube, tapered at both ends, 180 mm along its arc, on a flattened underside."),
    HouseholdObject("t_tool", t_tool, ABS, "orange", "other", "lying",
                    GraspSpec((-0.02, 0.0), Y, 0.015, "across the stem"),
                    "A T-shaped plastic tool: a 22 mm square stem with a 100 mm crossbar at one end."),
    HouseholdObject("l_bracket", l_bracket, STEEL, "grey", "other", "standing",
                    GraspSpec((-0.033, 0.0), X, 0.02, "across the upright leg's plate"),
                    "A steel L bracket, 4 mm plate, 70 x 50 mm legs, 30 mm wide; one leg flat, one upright."),
    HouseholdObject("wedge", wedge, WOOD, "wood", "other", "lying",
                    GraspSpec((0.0, 0.0), Y, 0.015, "across its width"),
                    "A wooden door wedge, 90 mm long, 45 mm wide, rising from 6 to 35 mm."),
    HouseholdObject("ring", ring, RUBBER, "black", "other", "lying",
                    GraspSpec((0.028, 0.0), X, 0.01, "across the ring's section"),
                    "A rubber ring lying flat, 71 mm across, a 15 mm round section."),
    HouseholdObject("small_box", small_box, CARDBOARD_BOX, "purple", "box-like", "lying",
                    GraspSpec((0.0, 0.0), Y, 0.015, "across its narrow side"),
                    "A small cardboard box, 65 x 45 x 30 mm, with contents."),
    HouseholdObject("plate", plate, CERAMIC, "white", "flat", "lying",
                    GraspSpec((0.083, 0.0), X, 0.01, "across the rim"),
                    "A 170 mm ceramic side plate, 25 mm high at the rim."),
    HouseholdObject("pen", pen, PEN, "black", "elongated", "lying",
                    GraspSpec((0.0, 0.0), Y, 0.007, "across the barrel, anywhere along it"),
                    "A pen-like hexagonal rod, 146 mm long (longer than the gripper opens), 12 mm across flats."),
)


# ---------------------------------------------------------------- writing


def _fmt(value: float) -> str:
    return f"{round(float(value), DECIMALS) + 0.0:.{DECIMALS}f}"


def finish(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    """Origin at the bottom centre, vertices on the micrometre grid, a watertight volume (or an error)."""
    lo, hi = mesh.bounds
    mesh = mesh.copy()
    mesh.apply_translation([-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, -lo[2]])
    vertices = np.round(np.asarray(mesh.vertices, dtype=np.float64), DECIMALS) + 0.0
    mesh = trimesh.Trimesh(vertices, np.asarray(mesh.faces), process=True)
    if not (mesh.is_watertight and mesh.is_volume):
        raise RuntimeError("a generated mesh is not a watertight volume")
    return mesh


def obj_text(name: str, mesh: trimesh.Trimesh) -> str:
    lines = [f"# bt_grasp household object '{name}', made by tools/make_household.py; metres, Z up, "
             "origin at the bottom centre",
             f"o {name}"]
    lines += [f"v {_fmt(x)} {_fmt(y)} {_fmt(z)}" for x, y, z in mesh.vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.faces]
    return "\n".join(lines) + "\n"


def catalogue_entry(obj: HouseholdObject, mesh: trimesh.Trimesh) -> list[str]:
    grasp = measure_grasp(mesh, obj.grasp, MAX_OPENING_M)
    mass_kg = obj.material.density_kg_m3 * float(mesh.volume)
    ext = mesh.extents
    rgb = ", ".join(f"{c:.2f}" for c in COLORS[obj.color])
    return [
        f"  {obj.name}:",
        f"    file: {obj.name}.obj",
        f"    description: \"{obj.description}\"",
        f"    shape_class: {obj.shape_class}",
        f"    rests: {obj.pose}",
        f"    extents_m: [{_fmt(ext[0])}, {_fmt(ext[1])}, {_fmt(ext[2])}]",
        f"    volume_m3: {float(mesh.volume):.9f}",
        f"    material: {obj.material.name}",
        f"    density_kg_m3: {obj.material.density_kg_m3:.1f}",
        f"    mass_kg: {mass_kg:.4f}",
        f"    friction: {obj.material.friction:.2f}",
        f"    color: {obj.color}",
        f"    rgb: [{rgb}]",
        "    grasp:",
        f"      point_m: [{', '.join(_fmt(v) for v in grasp.point_m)}]",
        f"      closing: [{', '.join(f'{v:.1f}' for v in grasp.closing)}]",
        f"      depth_m: {_fmt(grasp.depth_m)}",
        f"      width_m: {_fmt(grasp.width_m)}",
        f"      note: {grasp.note}",
    ]


def generate(out: Path) -> list[Path]:
    """Write every object's OBJ and the catalogue into ``out``; returns the written paths in order."""
    out.mkdir(parents=True, exist_ok=True)
    written = []
    catalogue = [
        "# bt_grasp's household object set (issue 28), made by tools/make_household.py: do not edit by hand;",
        "# change the script and run it again (tests/test_household_set.py checks the two agree).",
        "# Units: metres, kilograms. Each mesh: Z up, origin at the bottom centre (rests on z = 0).",
        "# mass_kg = density_kg_m3 x volume_m3 (the mesh's own volume; a mug is a shell, a bottle is full).",
        "# grasp: one top-down grasp, pads centred on point_m, closing along closing, reaching depth_m below it.",
        "version: 1",
        "objects:",
    ]
    for obj in OBJECTS:
        mesh = finish(obj.build())
        path = out / f"{obj.name}.obj"
        path.write_text(obj_text(obj.name, mesh), encoding="utf-8", newline="\n")
        written.append(path)
        catalogue += catalogue_entry(obj, mesh)
    path = out / CATALOGUE
    path.write_text("\n".join(catalogue) + "\n", encoding="utf-8", newline="\n")
    written.append(path)
    return written


def check(shipped: Path) -> list[str]:
    """Regenerate into a temporary folder; the problems found comparing with ``shipped`` (empty: identical)."""
    with tempfile.TemporaryDirectory(prefix="household-") as tmp:
        fresh = generate(Path(tmp))
        names = {p.name for p in fresh}
        problems = [f"{shipped / p.name} differs from what the script makes" for p in fresh
                    if not (shipped / p.name).is_file() or not filecmp.cmp(p, shipped / p.name, shallow=False)]
    if shipped.is_dir():
        problems += [f"{p} is not made by the script" for p in sorted(shipped.iterdir()) if p.name not in names]
    return problems


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0] if __doc__ else None)
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="folder to write into")
    parser.add_argument("--check", action="store_true", help="compare a fresh generation with --out, write nothing")
    args = parser.parse_args(argv)
    if args.out.exists() and not args.out.is_dir():
        print(f"{args.out}: --out names a file, not a folder", file=sys.stderr)
        return 2
    if args.check:
        problems = check(args.out)
        for problem in problems:
            print(problem, file=sys.stderr)
        if not problems:
            print(f"{args.out}: the shipped household set is what the script makes")
        return 1 if problems else 0
    for path in generate(args.out):
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
