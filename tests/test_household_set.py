"""The shipped household object set (issue 28): it is what tools/make_household.py makes, byte for byte, the script
is deterministic, and every object is a sane, graspable solid with a plausible mass and friction.

Fast, no simulator: the meshes are read from the shipped OBJ files with trimesh, the claims from objects.yaml.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import trimesh
import yaml
from scipy.spatial import ConvexHull

from bt_grasp.perception.config import GraspSettings
from bt_grasp.robot_description import MAX_OPENING_M
from bt_grasp.scene.colors import COLOR_NAMES

REPO = Path(__file__).resolve().parents[1]
TOOL = REPO / "tools" / "make_household.py"
SHIPPED = REPO / "bt_grasp" / "assets" / "household"
SHAPE_CLASSES = {"box-like", "cylinder-like", "elongated", "flat", "other"}
#: the play the grasp synthesis keeps between an object and the open pads (both sides together)
WIDEST_GRASP_M = MAX_OPENING_M - GraspSettings().width_margin_m
#: a tabletop object the UR5 handles: far smaller than the 1.0 x 1.4 m table, larger than a millimetre
LARGEST_EXTENT_M, SMALLEST_EXTENT_M = 0.25, 0.005


def _catalogue() -> dict[str, Any]:
    data = yaml.safe_load((SHIPPED / "objects.yaml").read_text(encoding="utf-8"))
    assert data["version"] == 1
    objects: dict[str, Any] = data["objects"]
    return objects


CATALOGUE = _catalogue()
NAMES = sorted(CATALOGUE)


def _mesh(name: str) -> trimesh.Trimesh:
    mesh = trimesh.load(SHIPPED / CATALOGUE[name]["file"], file_type="obj", force="mesh")
    assert isinstance(mesh, trimesh.Trimesh)
    return mesh


def _run_tool(*args: str, hash_seed: str = "0") -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONHASHSEED": hash_seed}
    return subprocess.run([sys.executable, str(TOOL), *args], capture_output=True, text=True, env=env, timeout=120,
                          check=False)


def _tree_bytes(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def test_the_shipped_set_is_what_the_script_makes() -> None:
    proc = _run_tool("--check")
    assert proc.returncode == 0, proc.stderr
    assert "is what the script makes" in proc.stdout


def test_check_mode_notices_an_edited_file(tmp_path: Path) -> None:
    assert _run_tool("--out", str(tmp_path)).returncode == 0
    plate = tmp_path / "plate.obj"
    plate.write_bytes(plate.read_bytes().replace(b"v ", b"v  ", 1))
    (tmp_path / "stray.obj").write_text("o stray\n", encoding="utf-8")
    proc = _run_tool("--check", "--out", str(tmp_path))
    assert proc.returncode == 1
    assert "plate.obj differs" in proc.stderr
    assert "stray.obj is not made by the script" in proc.stderr


def test_the_generator_is_deterministic(tmp_path: Path) -> None:
    # two processes with different hash seeds: nothing may depend on set or dict ordering, the clock or the run
    first, second = tmp_path / "first", tmp_path / "second"
    assert _run_tool("--out", str(first), hash_seed="1").returncode == 0
    assert _run_tool("--out", str(second), hash_seed="2").returncode == 0
    assert _tree_bytes(first) == _tree_bytes(second)
    assert _tree_bytes(first) == _tree_bytes(SHIPPED)


def test_at_least_twelve_objects_each_with_its_file() -> None:
    assert len(CATALOGUE) >= 12
    assert {p.name for p in SHIPPED.iterdir()} == {"objects.yaml"} | {e["file"] for e in CATALOGUE.values()}
    for required in ("mug", "bowl", "bottle", "can", "banana", "t_tool", "l_bracket", "wedge", "ring", "small_box",
                     "plate", "pen"):
        assert required in CATALOGUE


@pytest.mark.parametrize("name", NAMES)
def test_mesh_is_a_watertight_solid_resting_on_its_origin(name: str) -> None:
    mesh = _mesh(name)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.is_volume
    assert mesh.volume > 0
    lo, hi = mesh.bounds
    assert lo[2] == pytest.approx(0.0, abs=1e-6)  # rests on z = 0
    assert (lo[:2] + hi[:2]) == pytest.approx([0.0, 0.0], abs=2e-6)  # origin at the footprint's centre
    extents = hi - lo
    assert np.all(extents >= SMALLEST_EXTENT_M) and np.all(extents <= LARGEST_EXTENT_M)
    assert list(extents) == pytest.approx(CATALOGUE[name]["extents_m"], abs=1e-6)
    assert mesh.volume == pytest.approx(CATALOGUE[name]["volume_m3"], rel=1e-3)
    # the centre of mass lies over the footprint, inside the bounds: the object can stand as shipped
    assert np.all(mesh.center_mass >= lo) and np.all(mesh.center_mass <= hi)


@pytest.mark.parametrize("name", NAMES)
def test_it_rests_stably_as_shipped(name: str) -> None:
    """The centre of mass lies over the support polygon (the hull of what touches z = 0), at least 3 mm inside its
    edges: placed at height 0 the object stays as drawn instead of rolling or tipping."""
    mesh = _mesh(name)
    support = mesh.vertices[mesh.vertices[:, 2] <= 1e-4][:, :2]
    assert len(support) >= 3, "the object stands on a point or a line"
    hull = ConvexHull(support)
    # each hull facet is n . x + d <= 0 inside; the smallest -(n . com + d) is the distance to the nearest edge
    margin = -(hull.equations[:, :2] @ mesh.center_mass[:2] + hull.equations[:, 2]).max()
    assert margin >= 0.003


@pytest.mark.parametrize("name", NAMES)
def test_the_claimed_grasp_fits_the_gripper(name: str) -> None:
    """Cut the mesh with the grasp's vertical plane: between the open pads and within the pads' reach, the
    material is as wide as claimed, centred on the grasp point, and narrower than the gripper opens with play."""
    grasp = CATALOGUE[name]["grasp"]
    point = np.array(grasp["point_m"], dtype=np.float64)
    closing = np.array(grasp["closing"], dtype=np.float64)
    assert closing[2] == 0 and np.linalg.norm(closing) == pytest.approx(1.0)
    segments = trimesh.intersections.mesh_plane(_mesh(name), np.cross(closing, [0.0, 0.0, 1.0]), point)
    points = segments.reshape(-1, 3)
    along = (points - point) @ closing
    between = np.abs(along) <= MAX_OPENING_M / 2
    assert between.any(), "the grasp plane misses the object"
    assert points[between, 2].max() == pytest.approx(point[2], abs=5e-4)  # the point is on the material's top
    reached = between & (points[:, 2] >= point[2] - grasp["depth_m"])
    lo, hi = float(along[reached].min()), float(along[reached].max())
    assert hi - lo == pytest.approx(grasp["width_m"], abs=5e-4)
    assert (lo + hi) / 2 == pytest.approx(0.0, abs=5e-4)
    assert 0.002 <= hi - lo <= WIDEST_GRASP_M
    # the pads reach their depth without their tips touching the table
    assert point[2] - grasp["depth_m"] >= GraspSettings().fingertip_clearance_m - 1e-9


def test_the_pen_is_longer_than_the_gripper_opens_but_thin_enough_to_grasp_across() -> None:
    extents = _mesh("pen").extents
    assert max(extents) > MAX_OPENING_M + 0.03
    assert sorted(extents)[1] <= WIDEST_GRASP_M / 3
    assert CATALOGUE["pen"]["shape_class"] == "elongated"


def test_the_mug_is_hollow_and_its_mass_is_the_ceramic_shell() -> None:
    mug = _mesh("mug")
    radius, height = CATALOGUE["mug"]["grasp"]["width_m"] / 2, mug.extents[2]
    assert mug.volume < 0.5 * math.pi * radius**2 * height
    assert 0.15 <= CATALOGUE["mug"]["mass_kg"] <= 0.45  # an empty ceramic mug


@pytest.mark.parametrize("name", NAMES)
def test_mass_friction_colour_and_class_are_plausible(name: str) -> None:
    entry = CATALOGUE[name]
    mesh = _mesh(name)
    assert 300.0 <= entry["density_kg_m3"] <= 8000.0  # cardboard and contents to steel
    assert entry["mass_kg"] == pytest.approx(entry["density_kg_m3"] * mesh.volume, rel=2e-3)
    assert 0.005 <= entry["mass_kg"] <= 0.6  # held by friction: 0.6 kg needs about 7 N per pad at mu = 0.4
    assert 0.2 <= entry["friction"] <= 1.0
    assert entry["color"] in COLOR_NAMES
    assert tuple(entry["rgb"]) == pytest.approx(COLOR_NAMES[entry["color"]])
    assert entry["shape_class"] in SHAPE_CLASSES
    assert entry["rests"] in {"standing", "lying"}
    assert isinstance(entry["description"], str) and entry["description"].endswith(".")


HOUSEHOLD_SCENES = sorted((REPO / "scenes").glob("household*.yaml"))


@pytest.mark.parametrize("scene", HOUSEHOLD_SCENES, ids=lambda p: p.stem)
def test_household_scenes_use_the_catalogue_mass_and_friction(scene: Path) -> None:
    objects = yaml.safe_load(scene.read_text(encoding="utf-8"))["objects"]
    used = [o for o in objects if o.get("shape") == "mesh" and "assets/household/" in o["mesh"]]
    assert used, f"{scene.name} uses no object of the household set"
    for obj in used:
        path = (scene.parent / obj["mesh"]).resolve()
        assert path.parent == SHIPPED.resolve() and path.is_file()
        entry = CATALOGUE[path.stem]
        assert obj["mass_kg"] == pytest.approx(entry["mass_kg"], rel=0.01), obj["name"]
        assert obj["friction"] == pytest.approx(entry["friction"]), obj["name"]
