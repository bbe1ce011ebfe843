"""Synthetic runs for the recording tests: a small real py_trees tree and fake robot states, no simulator.

The tree (step by step, grasp_failures=1):

    Pick (Sequence, memory)
    ├── Detect (action)      tick 1 RUNNING, tick 2 SUCCESS
    ├── RetryGrasp (Retry, 3 failures)
    │   └── Grasp (action)   attempt 1: RUNNING, FAILURE "slipped"; attempt 2: RUNNING, SUCCESS
    └── Lift (action)        RUNNING, RUNNING, SUCCESS

With ``grasp_failures`` >= 3 the Retry gives up and the run fails with Grasp as the failed leaf.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
import py_trees
import pytest
import typer

from bt_grasp.cli import replay_cmd
from bt_grasp.errors import BtGraspError
from bt_grasp.recording import BoxMarker, PoseMarker, RunRecorder
from bt_grasp.tree.registry import NodeKind


class Scripted(py_trees.behaviour.Behaviour):
    """An action that runs ``running_ticks`` ticks per attempt and fails its first ``failures`` attempts."""

    def __init__(self, name: str, running_ticks: int, failures: int = 0, reason: str = "failed") -> None:
        super().__init__(name)
        self.running_ticks = running_ticks
        self.failures = failures
        self.reason = reason
        self.attempt = 0
        self.count = 0
        self.failure_reason: str | None = None

    def initialise(self) -> None:
        self.attempt += 1
        self.count = 0
        self.failure_reason = None

    def update(self) -> py_trees.common.Status:
        self.count += 1
        if self.count <= self.running_ticks:
            self.feedback_message = f"attempt {self.attempt}: step {self.count}"
            return py_trees.common.Status.RUNNING
        if self.attempt <= self.failures:
            self.feedback_message = f"attempt {self.attempt} failed"
            self.failure_reason = self.reason
            return py_trees.common.Status.FAILURE
        self.feedback_message = f"attempt {self.attempt} done"
        return py_trees.common.Status.SUCCESS


def build_tree(grasp_failures: int) -> py_trees.trees.BehaviourTree:
    grasp = Scripted("Grasp", running_ticks=1, failures=grasp_failures, reason="slipped")
    root = py_trees.composites.Sequence("Pick", memory=True, children=[
        Scripted("Detect", running_ticks=1),
        py_trees.decorators.Retry("RetryGrasp", child=grasp, num_failures=3),
        Scripted("Lift", running_ticks=2),
    ])
    return py_trees.trees.BehaviourTree(root)


def _kind(b: py_trees.behaviour.Behaviour) -> str:
    """The kind as ``bt_grasp.tree.introspect`` writes it (``NodeKind.value``)."""
    if isinstance(b, py_trees.composites.Composite):
        return NodeKind.CONTROL.value
    if isinstance(b, py_trees.decorators.Decorator):
        return NodeKind.DECORATOR.value
    return NodeKind.ACTION.value


class TreeAdapter:
    """What the tree runtime hands the recorder: uids, structure, per-tick node dicts."""

    def __init__(self, tree: py_trees.trees.BehaviourTree) -> None:
        self.tree = tree
        self.snapshot = py_trees.visitors.SnapshotVisitor()
        tree.visitors.append(self.snapshot)
        self.uids: dict[Any, int] = {}  # pre-order from 1, as BT.CPP numbers nodes
        self.paths: dict[Any, str] = {}
        self._paths(tree.root, "")

    def _paths(self, b: py_trees.behaviour.Behaviour, prefix: str) -> None:
        self.uids[b.id] = len(self.uids) + 1
        self.paths[b.id] = f"{prefix}{b.name}"
        for child in b.children:
            self._paths(child, f"{prefix}{b.name}/")

    def structure(self, b: py_trees.behaviour.Behaviour | None = None) -> dict[str, Any]:
        b = b or self.tree.root
        return {"uid": self.uids[b.id], "type": type(b).__name__, "name": b.name, "path": self.paths[b.id],
                "kind": _kind(b), "attributes": {"memory": True} if b is self.tree.root else {},
                "children": [self.structure(c) for c in b.children]}

    def nodes(self) -> list[dict[str, Any]]:
        out = []
        for b in self.tree.root.iterate():
            status = b.status.value if b.status != py_trees.common.Status.INVALID else "IDLE"
            out.append({"uid": self.uids[b.id], "path": self.paths[b.id], "type": type(b).__name__,
                        "name": b.name, "status": status, "feedback": b.feedback_message,
                        "failure_reason": getattr(b, "failure_reason", None) if status == "FAILURE" else None,
                        "ticked": b.id in self.snapshot.visited})
        out.sort(key=lambda n: n["uid"])
        return out


def robot_state(tick: int) -> dict[str, Any]:
    q = np.array([0.1 * np.sin(0.01 * tick + j) for j in range(6)])
    T = np.eye(4)
    T[:3, 3] = [0.4, 0.0, 0.3 + 0.001 * tick]
    return {"q_rad": q, "qd_rad_s": np.full(6, 0.01), "gripper_width_m": 0.08 - 0.0005 * min(tick, 100),
            "T_base_tcp": T}


DT_NS = 10_000_000  # 100 Hz


def record_run(
    path: Path, *, grasp_failures: int = 1, max_ticks: int = 50, images: bool = True,
    recorder_kwargs: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Record one synthetic run; returns what was written, for assertions."""
    tree = build_tree(grasp_failures)
    adapter = TreeAdapter(tree)
    written: dict[str, Any] = {"ticks": [], "blackboards": []}
    meta = {"seed": "7", "tree_file": "pick.xml", "scene_file": "table.yaml", "fault_plan": "none",
            "tick_rate_hz": "100", "command_line": "bt-grasp run --seed 7"}
    attachments = {"pick.xml": b"<root BTCPP_format=\"4\"/>", "table.yaml": b"objects: []\n"}
    with RunRecorder(path, metadata=meta, attachments=attachments, **(recorder_kwargs or {})) as rec:
        rec.write_tree_structure(0, adapter.structure())
        rec.write_transforms(0, [("base_link", "camera_color_optical_frame", np.eye(4))])
        bb: dict[str, Any] = {"big_cloud": np.zeros((500, 3)), "target": "cube"}
        for tick in range(1, max_ticks + 1):
            stamp = tick * DT_NS
            tree.tick()
            nodes = adapter.nodes()
            bb["attempt"] = tick // 3
            bb["T_base_object"] = np.eye(4) if tick < 4 else np.diag([1.0, 1.0, 1.0, 1.0]) * 1.0
            rec.write_tick(tick, stamp, nodes, dict(bb), robot_state(tick))
            written["ticks"].append(nodes)
            written["blackboards"].append(dict(bb))
            if images and tick % 5 == 1:
                rgb = np.zeros((24, 32, 3), np.uint8)
                rgb[:, :, 0] = tick
                rgb[4:10, 4:12] = (200, 50, 30)
                rec.write_color_image(stamp, rgb, "camera_color_optical_frame")
                depth = np.full((24, 32), 0.5 + 0.01 * tick, np.float32)
                depth[0, 0] = np.nan
                rec.write_depth(stamp, depth, "camera_color_optical_frame")
                rec.write_points(stamp, np.random.default_rng(tick).random((50, 3)), None, "base_link")
                rec.write_markers(stamp, [BoxMarker("cube", np.eye(4), (0.05, 0.05, 0.05), label="cube"),
                                          PoseMarker("g0", np.eye(4), label="top grasp")])
            for n in nodes:
                if n["ticked"] and n["status"] == "FAILURE" and n["name"] == "Grasp":
                    rec.write_event(stamp, "failure", {"leaf": "Grasp", "reason": n["failure_reason"]})
                    rec.write_fault(stamp, tick, {"name": "slip", "target": "gripper"})
            if tick == 2:
                rec.write_log(stamp, "INFO", "runner", "detected cube")
                rec.write_trajectory(stamp, "approach", [0.0, 0.5, 1.0], np.zeros((3, 6)), kind="planned")
            rec.flush_tick()
            status = tree.root.status
            if status in (py_trees.common.Status.SUCCESS, py_trees.common.Status.FAILURE):
                break
        success = tree.root.status == py_trees.common.Status.SUCCESS
        result = {"success": success, "reason": None if success else "grasp failed",
                  "failed_leaf": None if success else "Grasp", "ticks": tick, "sim_time_s": tick * 0.01,
                  "wall_time_s": 0.1, "retries": min(grasp_failures, 2), "object_lift_m": 0.1 if success else 0.0}
        rec.write_result(tick * DT_NS, result)
        written["result"] = result
        written["n_ticks"] = tick
    return written


def run_cli(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    """The replay command on a fresh app, with the error handling of bt_grasp.cli.main."""
    app = typer.Typer(pretty_exceptions_enable=False)
    replay_cmd.register(app)

    @app.callback()
    def _root() -> None:  # keep "replay" a sub-command, as in the real CLI
        pass

    try:
        app(args=args, standalone_mode=False)
        code = 0
    except BtGraspError as exc:
        print(f"bt-grasp: error: {exc}", file=sys.stderr)
        code = exc.exit_code
    captured = capsys.readouterr()
    return code, captured.out, captured.err
