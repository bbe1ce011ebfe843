"""Scene files are validated strictly: exit code 2 and one line naming the file, the place and the problem."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from bt_grasp.errors import ConfigError
from bt_grasp.scene.format import load_scene

BAD = Path(__file__).parent / "data" / "bad_scenes"

# file -> (expected line or None, a fragment the message must contain)
EXPECTED: dict[str, tuple[int | None, str]] = {
    "unknown_key.yaml": (6, "unknown key 'colr'; did you mean 'color'?"),
    "negative_size.yaml": (4, "objects[0].size_m[1]"),
    "missing_field.yaml": (2, "missing required key 'objects[0].pose'"),
    "wrong_type.yaml": (2, "physics.timestep_s"),
    "bad_yaml.yaml": (4, "invalid YAML"),
    "python_tag.yaml": (1, "unsupported YAML tag"),
    "unknown_shape.yaml": (3, "objects[0].shape"),
    "wrong_size_count.yaml": (2, "needs size_m with 2 numbers"),
    "unknown_color.yaml": (5, "unknown colour 'chartreuse'"),
    "duplicate_names.yaml": (None, "repeated: a"),
    "inverted_range.yaml": (7, "low <= high"),
    # found by the pre-review attack: a run of these never ended (10^4 to 10^7 physics steps a tick), or NaN and
    # infinity passed as numbers into the simulator
    "slow_physics.yaml": (1, "one tick would take 10000 physics steps (at most 100)"),
    "nan_gravity.yaml": (2, "physics.gravity_m_s2[0]: Input should be a finite number"),
    "inf_table.yaml": (2, "table.size_m[0]: Input should be a finite number"),
    "top_level_list.yaml": (1, "expected a mapping"),
    "empty.yaml": (None, "the file is empty"),
    "big_timestep.yaml": (2, "physics.timestep_s"),
    "bad_mount.yaml": (2, "camera.mount"),
    "binary.yaml": (None, "not UTF-8"),
}


def test_corpus_is_complete() -> None:
    assert sorted(p.name for p in BAD.glob("*.yaml")) == sorted(EXPECTED)


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_bad_scene_raises_config_error_with_place(name: str) -> None:
    line, fragment = EXPECTED[name]
    path = BAD / name
    with pytest.raises(ConfigError) as info:
        load_scene(path)
    message = str(info.value)
    assert message.startswith(str(path) + (f":{line}:" if line else ":")), message
    assert fragment in message, message
    assert "\n" not in message


def test_default_scene_loads(tabletop_scene_path: Path) -> None:
    scene = load_scene(tabletop_scene_path)
    assert [o.name for o in scene.objects] == ["red_box", "green_cylinder", "blue_box"]
    assert scene.physics.timestep_s <= 1 / 250


@pytest.mark.parametrize("name", ["unknown_key.yaml", "python_tag.yaml", "binary.yaml", "empty.yaml", "bad_yaml.yaml"])
def test_cli_exit_code_2_and_one_line(name: str, tmp_path: Path) -> None:
    path = BAD / name
    proc = subprocess.run(
        [sys.executable, "-m", "bt_grasp.cli.main", "scene", "render", str(path), "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith(f"bt-grasp: error: {path}"), lines[0]
    assert "Traceback" not in proc.stderr
    assert not any(tmp_path.iterdir()), "nothing is written for a bad scene"
