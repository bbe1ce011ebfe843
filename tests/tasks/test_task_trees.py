"""The shipped task trees: each loads on its scene, and its YAML twin (made by `bt-grasp tree convert`)
ticks identically to the XML, node by node, with the robot leaves replaced by the same stand-ins."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_grasp.behaviours import robot_registry
from bt_grasp.behaviours.library import check_tree_against_scene
from bt_grasp.bench.tasks import TASKS
from bt_grasp.clock import ManualClock
from bt_grasp.perception.results import Detection
from bt_grasp.scene.format import load_scene
from bt_grasp.tree.loader import load_tree

REPO = Path(__file__).resolve().parents[2]
# every leaf that needs the robot: RUNNING for 2 ticks, then SUCCESS; the object queries run for real on a
# list of two objects put where PerceiveAll would write it
STAND_INS = {spec.name: "Running:2" for spec in robot_registry(installed=False).specs() if spec.needs_robot}
SEEN = (
    Detection("red", (0, 0, 1, 1), (0.5, 0.1, 0.025), (0.05, 0.05, 0.05), 0.0, 100, 1.0),
    Detection("blue", (0, 0, 1, 1), (0.5, -0.1, 0.02), (0.06, 0.06, 0.04), 0.0, 100, 1.0),
)


@pytest.mark.parametrize("task", TASKS, ids=lambda t: t.name)
def test_task_tree_fits_its_scene(task) -> None:  # type: ignore[no-untyped-def]
    tree_path, scene_path = task.paths(REPO)
    scene = load_scene(scene_path)
    tree = load_tree(tree_path, robot_registry(), clock=ManualClock())
    check_tree_against_scene(tree.nodes(), scene)
    assert scene.calibration and (scene_path.parent / scene.calibration).is_file()


def _stream(path: Path) -> list[dict[str, str]]:
    clock = ManualClock()
    tree = load_tree(path, robot_registry(), substitutions=STAND_INS, clock=clock)
    tree.root_blackboard.set("seen", SEEN)
    tree.root_blackboard.set("support", SEEN[1])
    ticks = []
    for _ in range(400):
        status = tree.tick()
        ticks.append({node.bt_path: node.bt_state.value for node in tree.nodes()})
        if status.completed:
            break
        clock.advance_s(0.01)
    return ticks


@pytest.mark.parametrize("task", [t for t in TASKS if t.name != "pick"], ids=lambda t: t.name)
def test_yaml_twin_ticks_like_the_xml(task) -> None:  # type: ignore[no-untyped-def]
    xml = REPO / task.tree
    twin = xml.with_suffix(".yaml")
    assert twin.is_file(), f"{twin} is missing: make it with `bt-grasp tree convert {task.tree} {twin.name}`"
    a, b = _stream(xml), _stream(twin)
    assert len(a) == len(b) and len(a) > 10
    for tick, (x, y) in enumerate(zip(a, b, strict=True), start=1):
        assert x == y, f"tick {tick} differs"


def test_bench_tasks_refuses_an_unknown_task_in_one_line() -> None:
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-m", "bt_grasp.cli.main", "bench", "tasks", "--task", "juggle"],
                          capture_output=True, text=True, timeout=120, cwd=REPO)
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        "bt-grasp: error: Invalid value for '--task': Value error, 'juggle' is not one of 'pick', 'pick_and_place', "
        "'stack', 'sort_by_color', 'clear_table', 'clear_household'. (see `bt-grasp bench tasks --help`)"
    ]
