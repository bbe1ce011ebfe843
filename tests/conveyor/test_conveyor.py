"""The conveyor fixture: strict scene loading (bad input exits 2 with file:line), a belt that carries
objects by friction at its speed (physics only), and the visual-following pieces (track, PID, tracker)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from bt_grasp.behaviours.servo import Gains, PidLaw, TargetTrack, grasp_yaw
from bt_grasp.errors import ConfigError
from bt_grasp.perception.tracking import Footprint, _top_centre_from_hits
from bt_grasp.scene.format import load_scene

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "scenes/conveyor_follow.yaml"


def _scene_with(tmp_path: Path, old: str, new: str) -> Path:
    text = SCENE.read_text()
    assert old in text
    path = tmp_path / "bad_conveyor.yaml"
    path.write_text(text.replace(old, new))
    return path


@pytest.mark.parametrize(
    ("old", "new", "fragment"),
    [
        ("    speed_m_s: 0.05", "    speed_m_s: 2.5", "speed_m_s"),
        ("    speed_m_s: 0.05", "    speed_m_s: -0.1", "speed_m_s"),
        ("    friction: 0.8\nobjects", "    frictoin: 0.8\nobjects", "frictoin"),
        ("    direction: forward", "    direction: sideways", "direction"),
    ],
)
def test_bad_conveyor_fields_name_the_file_and_line(tmp_path: Path, old: str, new: str, fragment: str) -> None:
    path = _scene_with(tmp_path, old, new)
    with pytest.raises(ConfigError) as info:
        load_scene(path)
    text = str(info.value)
    line = next(i for i, t in enumerate(path.read_text().splitlines(), start=1) if new.split(":")[0].strip() in t
                and new.strip().split("\n")[0] in t)
    assert str(path) in text and f":{line}" in text and fragment in text, text


def test_a_belt_faster_than_physical_limits_exits_2_with_one_line(tmp_path: Path) -> None:
    path = _scene_with(tmp_path, "    speed_m_s: 0.05", "    speed_m_s: 3.0")
    proc = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "run", "trees/pick_from_conveyor.xml",
                           "--scene", str(path), "--quiet"], capture_output=True, text=True, timeout=300, cwd=REPO)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and str(path) in lines[0] and "speed_m_s" in lines[0], proc.stderr


def test_the_track_fits_position_and_velocity() -> None:
    track = TargetTrack("red", 0.05, 0.0, 0.05, 0.05, False)
    rng = np.random.default_rng(0)
    for k in range(12):
        t = k / 15
        track.add(t, np.array([0.5, -0.3 + 0.05 * t, 0.055]) + np.r_[rng.normal(0, 0.001, 2), 0.0])
    position, velocity = track.predict(1.0)
    assert velocity[:2] == pytest.approx([0.0, 0.05], abs=0.004)
    assert position == pytest.approx([0.5, -0.25, 0.055], abs=0.002)


def test_the_pid_feeds_the_target_velocity_forward_and_does_not_wind_up() -> None:
    law = PidLaw(Gains(kp=4.0, ki=1.0, kd=0.0))
    u = law.command(np.zeros(3), np.array([0.0, 0.05, 0.0]), 0.01)
    assert u == pytest.approx([0.0, 0.05, 0.0])
    for _ in range(300):  # a long approach from far away: outside the integral zone nothing accumulates
        law.command(np.array([0.2, 0.0, 0.0]), np.zeros(3), 0.01)
    assert np.all(law.integral == 0.0)
    fast = law.command(np.array([1.0, 1.0, -1.0]), np.zeros(3), 0.01)
    assert np.hypot(fast[0], fast[1]) == pytest.approx(0.30) and fast[2] == pytest.approx(-0.10)


def test_the_grasp_yaw_closes_across_the_narrow_side_without_flipping_the_wrist() -> None:
    track = TargetTrack("red", 0.05, np.deg2rad(30.0), 0.07, 0.04, False)
    assert np.rad2deg(grasp_yaw(track, np.deg2rad(200.0))) == pytest.approx(210.0)
    assert np.rad2deg(grasp_yaw(track, 0.0)) == pytest.approx(30.0)
    assert grasp_yaw(TargetTrack("red", 0.05, 0.3, 0.05, 0.05, True), 1.0) == 1.0


def test_the_far_edge_estimate_ignores_side_faces_on_the_cameras_side() -> None:
    # a 5 cm square top face centred at (0.5, 0) and, between it and the camera, a side face's hits
    u, v = np.meshgrid(np.linspace(-0.025, 0.025, 40), np.linspace(-0.025, 0.025, 40))
    top = np.stack([0.5 + u.ravel(), v.ravel(), np.full(u.size, 0.08)], axis=1)
    side = np.stack([0.5 - 0.025 - 0.02 * np.random.default_rng(1).random(600), np.linspace(-0.025, 0.025, 600),
                     np.full(600, 0.08)], axis=1)
    hits = np.vstack([top, side])
    x, y = _top_centre_from_hits(hits, np.array([0.43, 0.0]), Footprint(0.05, 0.05, 0.0))
    assert abs(x - 0.5) < 0.0015 and abs(y) < 0.0015
    assert abs(float(np.median(hits[:, 0])) - 0.5) > 0.003  # the plain median is pulled towards the camera


@pytest.mark.sim
def test_the_belt_carries_objects_by_friction_at_its_speed() -> None:
    from bt_grasp.sim.oracle import GroundTruthOracle
    from bt_grasp.sim.world import World

    world = World.from_file(SCENE, 4)
    oracle = GroundTruthOracle(world)
    world.step(world.steps_per_tick * 20)  # settle and get up to speed
    start = {n: oracle.T_world_object(n)[:3, 3] for n in oracle.object_names()}
    world.step(world.steps_per_tick * 200)  # 2 s
    for name, p0 in start.items():
        p1 = oracle.T_world_object(name)[:3, 3]
        assert p1[1] - p0[1] == pytest.approx(0.05 * 2.0, rel=0.05), name  # +y at 5 cm/s
        assert abs(p1[0] - p0[0]) < 0.002, name
        spec = world.config.object_spec(name)
        assert spec is not None
        assert p1[2] == pytest.approx(0.03 + spec.height_m / 2, abs=0.002), name  # resting on the belt


@pytest.mark.sim
@pytest.mark.slow
@pytest.mark.parametrize("scene", ["conveyor.yaml", "conveyor_eye_in_hand.yaml"])
def test_pick_from_the_conveyor_succeeds_by_physics_and_logs_the_intercept(scene: str, tmp_path: Path) -> None:
    from bt_grasp.episode import EpisodeRequest, run_episode
    from bt_grasp.recording.reader import open_log

    log = tmp_path / "conveyor.mcap"
    request = EpisodeRequest(tree=REPO / "trees/pick_from_conveyor.xml", scene=REPO / "scenes" / scene, seed=2,
                             log=log)
    result = run_episode(request)
    assert result.success, result
    run = open_log(log)
    phases = [e["payload"]["phase"] for e in run.events if e.get("kind") == "servo"
              and e["payload"].get("leaf") == "intercept"]
    assert [p for i, p in enumerate(phases) if i == 0 or p != phases[i - 1]] == [
        "approach", "descend", "close", "lift", "done"]


@pytest.mark.sim
@pytest.mark.slow
def test_sort_from_the_conveyor_puts_objects_in_the_bin_by_physics(tmp_path: Path) -> None:
    from bt_grasp.episode import EpisodeRequest, run_episode

    # two objects, not the scene's four: the same tree and belt, half the simulated time
    scene = tmp_path / "conveyor_sort_2.yaml"
    text = (REPO / "scenes/conveyor_sort.yaml").read_text()
    assert "goal: {kind: collect, into: bin, count: 4}" in text
    scene.write_text(text.replace("count: 4}", "count: 2}").replace(
        "calibration: tabletop.calibration.yaml", f"calibration: {REPO / 'scenes/tabletop.calibration.yaml'}"))
    result = run_episode(EpisodeRequest(tree=REPO / "trees/sort_from_conveyor.xml", scene=scene, seed=1))
    assert result.success, result
    assert "2 of 2 placed in bin" in str(result.judged.to_json())


def test_the_benchmark_changes_only_the_belt_speed(tmp_path: Path) -> None:
    from bt_grasp.bench.follow import scene_at_speed

    path = scene_at_speed(REPO, "eye-in-hand", 0.1, tmp_path)
    scene, original = load_scene(path), load_scene(REPO / "scenes/conveyor_follow_eye_in_hand.yaml")
    assert scene.fixtures[0].speed_m_s == 0.1  # type: ignore[union-attr]
    assert scene.model_copy(update={"fixtures": original.fixtures, "calibration": original.calibration}) == original
    assert Path(str(scene.calibration)).is_file()
