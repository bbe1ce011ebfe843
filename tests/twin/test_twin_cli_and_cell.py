"""`bt-grasp twin`'s command line (bad input is one sentence, exit 2; another host is warned about) and the cell
file it writes (strict, loadable, matching the scene)."""

from __future__ import annotations

import socket
import subprocess
import sys
from pathlib import Path

import pytest

from bt_grasp.bench.twin_process import TwinProcess, free_loopback
from bt_grasp.cell.format import load_cell
from bt_grasp.cli.twin_cmd import remote_warning
from bt_grasp.errors import ConfigError
from tests.twin.conftest import REPO


def _twin_cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "twin", *args], cwd=REPO, capture_output=True,
                          text=True, timeout=120)


def test_a_bad_scene_is_one_sentence_and_exit_2(tmp_path: Path) -> None:
    scene = tmp_path / "bad.yaml"
    scene.write_text("version: 2\nrobot:\n  home_q_rad: [0, 0]\n")
    done = _twin_cli("--scene", str(scene))
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.count("\n") == 1 and done.stderr.startswith(f"bt-grasp: error: {scene}:3")


@pytest.mark.sim
def test_a_taken_address_is_one_sentence_and_exit_2() -> None:
    host = free_loopback(salt=5)
    with socket.socket() as holder:
        holder.bind((host, 29999))
        holder.listen(1)
        done = _twin_cli("--scene", "scenes/tabletop.yaml", "--host", host)
    assert done.returncode == 2
    assert done.stderr == (f"bt-grasp: error: --host: cannot serve on {host}:29999 (dashboard): Address already in "
                           "use (another twin or a robot driver holds the port; give another loopback address such as "
                           "127.0.0.2)\n")


def test_another_host_than_loopback_is_warned_about() -> None:
    text = remote_warning("0.0.0.0")
    assert "0.0.0.0" in text and "no authentication" in text and "ssh -L" in text


@pytest.mark.sim
def test_the_written_cell_file_loads_and_matches_the_scene(twin: TwinProcess) -> None:
    cell = load_cell(twin.cell_path)
    assert cell.arm.model == "ur5" and cell.arm.address == twin.host
    assert cell.arm.tcp_pose == (0.0, 0.0, 0.1745, 0.0, 0.0, 0.0)  # the 2F-85's, as the twin's controller has it
    assert cell.gripper.model == "robotiq-2f85" and cell.gripper.stroke_m == 0.085
    assert cell.gripper.pad_size_m == (0.022, 0.00635, 0.0375)
    assert cell.camera.kind == "twin" and cell.camera.mount == "eye-to-hand"
    assert cell.calibration is not None
    # a copy of the scene's, of the cell's own beside it: `calibrate --cell` replaces the copy, never the scene's file
    # (scenes/tabletop.calibration.yaml links to the one bt_grasp ships in bt_grasp/assets/)
    own = twin.cell_path.parent / cell.calibration
    assert own.parent == twin.cell_path.parent and own.name.endswith(".calibration.yaml") and not own.is_symlink()
    assert own.read_bytes() == (REPO / "scenes" / "tabletop.calibration.yaml").read_bytes()
    assert cell.table_plane.normal == (0.0, 0.0, 1.0) and cell.table_plane.offset_m == 0.0
    assert cell.workspace.min_m == (0.25, -0.35, 0.0) and cell.workspace.max_m == (0.75, 0.35, 0.5)
    assert cell.workspace.objects_up_to_m == 0.30 and cell.table_plane.x_m == (-0.15, 0.85)
    assert cell.camera.eye_to_hand is not None and cell.camera.eye_to_hand.position_m == (1.05, 0.0, 0.75)
    assert cell.arm.home_q_rad != (0.0, -1.9, 1.9, -1.57, -1.57, 0.0)  # the 2F-85 is longer: the wrist stands higher


def test_a_cell_file_is_loaded_strictly(tmp_path: Path) -> None:
    from bt_grasp.scene.format import load_scene
    from bt_grasp.sim.twin.cell_writer import write_cell
    from bt_grasp.sim.twin.config import TwinConfig

    scene_path = REPO / "scenes" / "pick_and_place.yaml"
    path = write_cell(load_scene(scene_path), scene_path, TwinConfig(), tmp_path / "cell.yaml")
    cell = load_cell(path)
    assert [f.name for f in cell.fixtures] == ["target_marker"] and cell.fixtures[0].kind == "marker"
    text = path.read_text()
    path.write_text(text.replace("  payload_kg:", "  payload_kgs:"))
    with pytest.raises(ConfigError, match=r"cell.yaml:\d+: .*payload_kgs"):
        load_cell(path)
