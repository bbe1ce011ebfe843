"""A non-editable install holds every file the package reads: each data file under bt_grasp/ (everything that is
not Python source) matches one of pyproject.toml's package-data globs, and the files the code names by path under
bt_grasp/assets (the gripper URDF, the household set) are among them."""

from __future__ import annotations

import glob
import re
import subprocess
import tomllib
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PKG = REPO / "bt_grasp"


def packaged() -> set[str]:
    """The files setuptools copies as bt_grasp's package data (its globs, relative to the package, recursive)."""
    patterns = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]["bt_grasp"]
    out: set[str] = set()
    for pattern in patterns:
        out |= {p for p in glob.glob(pattern, root_dir=PKG, recursive=True) if (PKG / p).is_file()}
    return out


def data_files() -> set[str]:
    """Every file of the package in the repository (tracked or new, not ignored) that is not Python source."""
    listed = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard", "bt_grasp"], cwd=REPO,
                            capture_output=True, text=True, check=True).stdout.split()
    return {str(Path(f).relative_to("bt_grasp")) for f in listed
            if not f.endswith(".py") and (REPO / f).is_file()}


def test_every_data_file_of_the_package_is_package_data() -> None:
    missing = sorted(data_files() - packaged())
    assert not missing, f"not in pyproject.toml's [tool.setuptools.package-data]: {missing}"


def test_the_assets_the_code_opens_are_package_data() -> None:
    opened: set[str] = set()
    for source in PKG.rglob("*.py"):
        text = source.read_text()
        # files("bt_grasp") / "assets" / "gripper.urdf" and the like
        for parts in re.findall(r'files\("bt_grasp"\)((?:\s*/\s*"[^"]+")+)', text):
            opened.add("/".join(re.findall(r'"([^"]+)"', parts)))
    assert "assets/gripper.urdf" in opened, opened
    assert {p for p in opened if p.startswith("assets/")} <= packaged()
    assert {f"assets/household/{p.name}" for p in (PKG / "assets" / "household").iterdir()} <= packaged()


def test_the_check_would_catch_a_missing_glob() -> None:
    text = (REPO / "pyproject.toml").read_text()
    assert '"assets/*"' in text
    patterns = tomllib.loads(text)["tool"]["setuptools"]["package-data"]["bt_grasp"]
    without = [p for p in patterns if p != "assets/*"]
    covered = {p for pattern in without for p in glob.glob(pattern, root_dir=PKG, recursive=True)}
    assert "assets/gripper.urdf" not in covered
