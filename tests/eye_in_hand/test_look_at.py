"""LookAt's view geometry (no simulator), and the eye-in-hand pick in the simulator: the XML tree and its
YAML twin succeed by physics and tick identically on the same seed."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bt_grasp.behaviours.viewing import parse_point, tool_pose_for_view
from bt_grasp.geometry import T_from_xyz_rpy

REPO = Path(__file__).resolve().parents[2]
SCENE = REPO / "scenes/eye_in_hand.yaml"
T_TOOL_CAMERA = T_from_xyz_rpy(np.array([-0.07, 0.0, 0.01]), np.deg2rad([0.0, 12.0, 0.0]))


@pytest.mark.parametrize("point", [(0.5, 0.0, 0.0), (0.4, -0.25, 0.02), (0.45, 0.2, 0.05)])
@pytest.mark.parametrize("distance", [0.4, 0.62])
def test_the_view_puts_the_point_on_the_optical_axis_at_the_distance(point: tuple[float, ...], distance: float
                                                                      ) -> None:
    p = np.array(point)
    T_tool = tool_pose_for_view(p, distance, T_TOOL_CAMERA)
    assert T_tool[:3, 2] @ np.array([0.0, 0.0, -1.0]) == pytest.approx(1.0)  # the tool points down
    assert T_tool[:3, 0] @ np.array([p[0], p[1], 0.0]) > 0  # tool x points away from the base
    T_cam = T_tool @ T_TOOL_CAMERA
    in_cam = np.linalg.inv(T_cam) @ np.array([*p, 1.0])
    assert in_cam[:2] == pytest.approx([0.0, 0.0], abs=1e-9)
    assert in_cam[2] == pytest.approx(distance)


def test_view_points_parse_like_btcpp_vectors() -> None:
    assert parse_point("0.5;0.1;0") == pytest.approx([0.5, 0.1, 0.0])
    assert parse_point("0.5, 0.1, 0") == pytest.approx([0.5, 0.1, 0.0])
    assert parse_point("workspace") is None and parse_point("1;2") is None and parse_point("a;b;c") is None


@pytest.mark.sim
@pytest.mark.slow
def test_eye_in_hand_pick_xml_and_yaml_twins_succeed_and_tick_identically(tmp_path: Path) -> None:
    from bt_grasp.episode import EpisodeRequest, run_episode
    from bt_grasp.recording.reader import open_log

    streams = []
    for tree in ("trees/pick_eye_in_hand.xml", "trees/pick_eye_in_hand.yaml"):
        log = tmp_path / f"{Path(tree).suffix[1:]}.mcap"
        request = EpisodeRequest(tree=REPO / tree, scene=SCENE, seed=3, log=log,
                                 blackboard={"color": "red", "lift_height": 0.15})
        result = run_episode(request)
        assert result.success, result
        run = open_log(log)
        paths = {uid: info.path for uid, info in run.structures[0].nodes().items()}
        streams.append([{paths[n.uid]: n.status for n in tick.nodes if n.ticked} for tick in run.ticks])
    assert streams[0] == streams[1]
    # the survey, the first look, the close view and the refining perception each succeeded, in that order
    # (coarse to fine)
    first_success: dict[str, int] = {}
    for i, tick in enumerate(streams[0]):
        for path, status in tick.items():
            for name in ("survey", "find", "close_view", "refine"):
                if path.rsplit("/", 1)[-1].split("@")[0] == name and str(status).endswith("SUCCESS"):
                    first_success.setdefault(name, i)
    assert sorted(first_success, key=first_success.__getitem__) == ["survey", "find", "close_view", "refine"], (
        first_success
    )


_VIEW_TREE = """<root BTCPP_format="4" main_tree_to_execute="T">
  <BehaviorTree ID="T">
    <Sequence>
      <LoadCalibration file="{calibration_file}"/>
      <LookAt view="%s"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


@pytest.mark.parametrize(("view", "fragment"), [("1.6;0;0.2", "out of the arm's reach"),
                                                ("over there", "neither 'workspace' nor a point")])
def test_a_bad_literal_view_exits_2_with_file_and_line(tmp_path: Path, view: str, fragment: str) -> None:
    import subprocess
    import sys

    tree = tmp_path / "far.xml"
    tree.write_text(_VIEW_TREE % view)
    log = tmp_path / "run.mcap"
    proc = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "run", str(tree), "--scene", str(SCENE),
                           "--log", str(log)], capture_output=True, text=True, timeout=300, cwd=REPO)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and f"{tree}:5" in lines[0] and fragment in lines[0], proc.stderr
    assert not log.exists()


@pytest.mark.sim
def test_an_unreachable_view_from_the_blackboard_fails_with_ik_unreachable(tmp_path: Path) -> None:
    from bt_grasp.episode import EpisodeRequest, run_episode

    tree = tmp_path / "far.xml"
    tree.write_text(_VIEW_TREE % "{far}")
    request = EpisodeRequest(tree=tree, scene=SCENE, seed=0, blackboard={"color": "red", "far": "1.6;0;0.2"})
    result = run_episode(request)
    assert not result.success and result.reason == "IK_UNREACHABLE" and result.failed_leaf == "LookAt"
    assert result.ticks <= 3  # refused before moving
