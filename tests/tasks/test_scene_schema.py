"""Scene format version 2: goal, fixtures, touching objects, the calibration beside the scene; bad input."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from bt_grasp.errors import ConfigError
from bt_grasp.scene.fixtures import Tray
from bt_grasp.scene.format import Scene, load_scene
from bt_grasp.scene.goals import PickGoal

REPO = Path(__file__).resolve().parents[2]
BAD = REPO / "tests" / "data" / "bad_task_scenes"

# file -> (expected line or None, a fragment the message must contain)
EXPECTED: dict[str, tuple[int | None, str]] = {
    "unknown_goal_kind.yaml": (4, "'juggle'"),
    "unknown_object.yaml": (8, "object 'green_box', which is not in the scene"),
    "unknown_fixture.yaml": (10, "fixture 'right_tray', which is not in the scene"),
    "place_off_table.yaml": (7, "is off the table"),
    "place_unreachable.yaml": (7, "is out of reach"),
    "into_a_marker.yaml": (6, "only a tray or a bin holds objects"),
    "unknown_fixture_kind.yaml": (3, "'shelf'"),
    "fixture_unknown_key.yaml": (7, "unknown key 'wall_heigth_m'; did you mean 'wall_height_m'?"),
    "v1_with_goal.yaml": (4, "add 'version: 2' at the top"),
    "future_version.yaml": (1, "newer than this bt_grasp reads"),
    "place_two_targets.yaml": (6, "exactly one of 'at'"),
    "stack_on_itself.yaml": (7, "cannot be stacked on itself"),
}


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_bad_task_scene_is_one_sentence_with_its_line(name: str) -> None:
    line, fragment = EXPECTED[name]
    path = BAD / name
    with pytest.raises(ConfigError) as info:
        load_scene(path)
    message = str(info.value)
    assert message.startswith(f"{path}:{line}:" if line else f"{path}:"), message
    assert fragment in message, message
    assert "\n" not in message


def test_a_first_format_scene_still_loads(tmp_path: Path) -> None:
    old = tmp_path / "old.yaml"
    old.write_text("name: old\nobjects:\n  - {name: a, shape: box, size_m: [0.05, 0.05, 0.05], color: red, "
                   "pose: {xy_m: [0.5, 0.0]}}\n")
    scene = load_scene(old)
    assert scene.version == 1 and scene.goal is None and scene.fixtures == ()
    assert scene.effective_goal("red") == PickGoal(kind="pick", color="red")


def test_tray_parts_enclose_its_floor() -> None:
    tray = Tray(kind="tray", name="t", center_xy_m=(0.4, 0.45), yaw_deg=90, inner_size_m=(0.2, 0.1))
    parts = {p.name: p for p in tray.parts()}
    assert set(parts) == {"t/floor", "t/wall_x_minus", "t/wall_x_plus", "t/wall_y_minus", "t/wall_y_plus"}
    # yawed 90 degrees: the 0.2 m inner side lies along world y
    assert tray.contains_xy((0.4, 0.45 + 0.09)) and not tray.contains_xy((0.4 + 0.09, 0.45))
    wall = parts["t/wall_x_plus"].T_world_part[:3, 3]
    assert np.allclose(wall[:2], (0.4, 0.45 + 0.105), atol=1e-9)


def test_objects_may_touch_when_the_scene_says_so() -> None:
    from bt_grasp.sim.objects import draw_poses

    def scene(gap: float | None) -> Scene:
        data = {"version": 2, "objects": [
            {"name": "a", "shape": "box", "size_m": [0.05, 0.05, 0.05], "color": "red", "pose": {"xy_m": [0.5, 0.0]}},
            {"name": "b", "shape": "box", "size_m": [0.05, 0.05, 0.05], "color": "blue", "pose": {"xy_m": [0.55, 0.0]}},
        ]}
        if gap is not None:
            data["object_gap_m"] = gap
        return Scene.model_validate(data)

    placed = draw_poses(scene(0.0).objects, np.random.default_rng(0), 0.0, "touching", 0.0)
    assert np.allclose(placed[1].T_world_object[:2, 3], (0.55, 0.0))
    with pytest.raises(ConfigError, match="cannot place object 'b'"):
        draw_poses(scene(None).objects, np.random.default_rng(0), 0.0, "touching", None)


def _bt(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", *args], capture_output=True, text=True,
                          timeout=300, cwd=REPO)


def test_run_with_a_missing_scene_calibration_exits_2_naming_the_scene_line(tmp_path: Path) -> None:
    scene = BAD / "missing_calibration.yaml"
    log = tmp_path / "run.mcap"
    proc = _bt("run", "trees/pick.xml", "--scene", str(scene), "--log", str(log))
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"bt-grasp: error: {scene}:2:"), proc.stderr
    assert "bt-grasp calibrate" in lines[0]
    assert not log.exists()


def test_a_calibration_for_another_camera_pose_exits_2(tmp_path: Path) -> None:
    text = (REPO / "scenes" / "tabletop.yaml").read_text().replace("position_m: [1.05, 0.0, 0.75]",
                                                                    "position_m: [1.05, 0.3, 0.75]")
    scene = tmp_path / "moved_camera.yaml"
    scene.write_text(text.replace("calibration: tabletop.calibration.yaml\n", ""))
    proc = _bt("run", "trees/pick.xml", "--scene", str(scene), "--calibration",
               str(REPO / "scenes" / "tabletop.calibration.yaml"))
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "made for another camera pose" in lines[0], proc.stderr


@pytest.mark.sim
def test_the_newcomer_command_succeeds_with_no_other_flag() -> None:
    """`bt-grasp run trees/pick.xml --scene scenes/tabletop.yaml`: the scene names its shipped calibration."""
    proc = _bt("run", "trees/pick.xml", "--scene", "scenes/tabletop.yaml", "--quiet")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "SUCCESS" in proc.stdout
