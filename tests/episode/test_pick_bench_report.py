"""`bench pick`'s choice of what to pick (never ground truth) and its per-object report (no simulator runs)."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

from bt_grasp.bench.pick import _per_object, default_pick_trees
from bt_grasp.scene.format import load_scene
from bt_grasp.scene.run_goal import default_color

REPO = Path(__file__).resolve().parents[2]


def test_a_scene_with_mesh_objects_picks_any_object_and_primitives_keep_red() -> None:
    assert default_color(load_scene(REPO / "scenes" / "tabletop.yaml").objects) == "red"
    assert default_color(load_scene(REPO / "tests" / "data" / "scenes" / "bottle_place.yaml").objects) == ""


def _run(seed: int, obj: str | None, success: bool, reason: str | None = None, leaf: str | None = None,
         judge: tuple[tuple[str, bool, str], ...] = ()) -> SimpleNamespace:
    return SimpleNamespace(seed=seed, success=success, reason=reason, failed_leaf=leaf,
                           tree_status="SUCCESS" if reason is None else "FAILURE",
                           judged=SimpleNamespace(object_name=obj, conditions=judge))


def test_per_object_counts_and_says_why_each_failure_failed() -> None:
    runs = [
        _run(0, "can", True),
        _run(1, "can", False, "GRASP_EMPTY", "Grasp", (("held", False, "can not between the fingers"),)),
        _run(2, "bowl", False, "NOTHING_TO_GRASP", "PlanGrasp"),
        _run(3, None, False, None, None, (("lifted", False, "rose 1.0 cm of 15.0 cm"),)),
        _run(4, "can", True),
    ]
    report = _per_object(runs)  # type: ignore[arg-type]
    assert list(report) == ["(none)", "bowl", "can"]
    assert (report["can"]["runs"], report["can"]["successes"]) == (3, 2)
    assert report["can"]["failures"] == {1: "GRASP_EMPTY (Grasp); judge: held: can not between the fingers"}
    assert report["bowl"]["failure_reasons"] == {"NOTHING_TO_GRASP": 1}
    assert report["(none)"]["failures"] == {3: "tree SUCCESS; judge: lifted: rose 1.0 cm of 15.0 cm"}


def test_the_learned_detector_runs_the_pick_by_class_beside_the_geometric_tree_when_no_tree_is_named() -> None:
    """The issue's `bench pick --scene scenes/household.yaml --detector learned --seeds 100` compares the learned
    detector's pick by class with the geometric detector on the same targets, with no --tree."""
    assert default_pick_trees("learned") == [Path("trees/pick_class.xml"), Path("trees/pick_with_recovery.xml")]
    assert default_pick_trees("geometric") == [Path("trees/pick.xml"), Path("trees/pick_with_recovery.xml")]
    for tree in (*default_pick_trees("learned"), *default_pick_trees()):
        assert (REPO / tree).is_file()
