"""The code fingerprint covers what changes a run (issue 22): every file's content in the package (shaders,
assets, data, not only ``.py``) and the dependencies' versions; a modification time alone changes nothing.
Edits are made in a copy of the package in a temporary folder."""

from __future__ import annotations

import os
import shutil
import time
from pathlib import Path

import pytest

import bt_grasp.process.code_fingerprint as cf
from bt_grasp.campaign.environment import environment
from bt_grasp.process.code_fingerprint import DEPENDENCIES, code_fingerprint, package_root
from bt_grasp.resident.protocol import code_version


@pytest.fixture
def package(tmp_path: Path) -> Path:
    copy = tmp_path / "bt_grasp"
    shutil.copytree(package_root(), copy, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    return copy


def _edit_same_size(path: Path) -> None:
    data = bytearray(path.read_bytes())
    data[-2] = ord("x") if data[-2] != ord("x") else ord("y")
    path.write_bytes(bytes(data))


@pytest.mark.parametrize("name", ["sim/shaders/gbuffer.frag", "assets/gripper.urdf",
                                  "foxglove/layouts/bt_grasp.layout.json", "bench/data/bench_plan_labels.json",
                                  "geometry.py"])
def test_changing_a_files_content_changes_the_fingerprint(package: Path, name: str) -> None:
    before = code_fingerprint(package)
    path = package / name
    original = path.read_bytes()
    _edit_same_size(path)
    assert code_fingerprint(package) != before, f"an edit of {name} went unseen"
    path.write_bytes(original)
    assert code_fingerprint(package) == before, "the same content again is the same code"


def test_touching_a_file_without_changing_it_does_not(package: Path) -> None:
    before = code_fingerprint(package)
    for name in ("sim/shaders/gbuffer.frag", "assets/gripper.urdf", "geometry.py"):
        info = (package / name).stat()
        os.utime(package / name, ns=(info.st_atime_ns, info.st_mtime_ns + 10**9 * 3600))
    assert code_fingerprint(package) == before


def test_an_edit_that_keeps_size_and_modification_time_is_still_seen(package: Path) -> None:
    """The in-process cache is keyed by the file's change time too (which no user call can set back)."""
    path = package / "sim/shaders/gbuffer.frag"
    before = code_fingerprint(package)
    info = path.stat()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:  # the file system's clock must have moved on since the copy was made
        probe = package.parent / "probe"
        probe.write_bytes(b"")
        if probe.stat().st_ctime_ns != info.st_ctime_ns:
            break
    _edit_same_size(path)
    os.utime(path, ns=(info.st_atime_ns, info.st_mtime_ns))
    assert path.stat().st_size == info.st_size and path.stat().st_mtime_ns == info.st_mtime_ns
    assert code_fingerprint(package) != before


def test_a_new_or_removed_file_changes_it_and_pycache_does_not(package: Path) -> None:
    before = code_fingerprint(package)
    cache = package / "sim" / "__pycache__"
    cache.mkdir(exist_ok=True)
    (cache / "world.cpython-311.pyc").write_bytes(b"derived from the sources")
    assert code_fingerprint(package) == before
    (package / "assets" / "extra.obj").write_text("v 0 0 0\n")
    assert code_fingerprint(package) != before
    (package / "assets" / "extra.obj").unlink()
    assert code_fingerprint(package) == before
    (package / "sim/shaders/composite.vert").rename(package / "sim/shaders/composite2.vert")
    assert code_fingerprint(package) != before, "a renamed file is other code"


@pytest.mark.parametrize("name", DEPENDENCIES)
def test_a_different_dependency_version_changes_it(package: Path, monkeypatch: pytest.MonkeyPatch, name: str) -> None:
    before = code_fingerprint(package)
    real = cf.library_version
    monkeypatch.setattr(cf, "library_version", lambda n: "0.0.0-other" if n == name else real(n))
    assert code_fingerprint(package) != before


def test_the_dependencies_are_the_installed_ones() -> None:
    versions = cf.dependency_versions()
    assert set(versions) >= {"sapien", "py-trees", "numpy", "open3d", "pin", "coal", "ompl", "ruckig", "mcap", "scipy"}
    missing = [name for name, v in versions.items() if v == "?"]
    assert missing == [], f"not installed (a misspelt distribution name?): {missing}"


def test_the_resident_and_the_campaign_rows_use_the_one_fingerprint() -> None:
    assert code_version() == code_fingerprint() == environment()["code"]
