"""What a log records about the run that made it: inputs, versions, commit (enough to run it again)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from bt_grasp.episode.request import EpisodeRequest
from bt_grasp.episode.result import goal_json
from bt_grasp.files.bounded_io import read_user_file
from bt_grasp.process.environment import versions_line
from bt_grasp.scene.format import Scene
from bt_grasp.scene.goals import Goal
from bt_grasp.tree.loader import LoadedTree


def git_commit() -> str:
    try:
        proc = subprocess.run(
            ["git", "rev-parse", "HEAD"], capture_output=True, text=True, timeout=5, cwd=Path(__file__).parent
        )
        return proc.stdout.strip() if proc.returncode == 0 else ""
    except (OSError, subprocess.SubprocessError):
        return ""


def run_metadata(request: EpisodeRequest, scene: Scene, tree: LoadedTree, calibration: Path | None,
                 goal: Goal) -> dict[str, str]:
    r = request
    return {
        "seed": str(r.seed),
        "tree_file": str(r.tree),
        "scene_file": str(r.scene),
        "calibration_file": str(calibration or ""),
        "fault_plan": str(r.faults or ""),
        "inject": ";".join(r.inject),
        "blackboard": json.dumps(dict(r.blackboard), sort_keys=True, default=str),
        "goal": json.dumps(goal_json(goal), sort_keys=True),
        "max_ticks": str(r.max_ticks),
        "command_line": " ".join(r.argv or sys.argv),
        "tick_rate_hz": str(scene.physics.control_rate_hz),
        "versions": versions_line(),
        "git_commit": git_commit(),
        "main_tree": tree.main_tree,
        "leaves": ";".join(r.leaves),
    }


def run_attachments(request: EpisodeRequest, tree: LoadedTree, calibration: Path | None) -> dict[str, bytes]:
    """The exact bytes of every input file (``replay --resim`` runs them again)."""
    files: dict[str, bytes] = {}
    for name, text in tree.sources.items():
        files[f"tree/{Path(name).name}"] = text.encode()
    files[f"scene/{request.scene.name}"] = read_user_file(request.scene)  # bounded, as when they were loaded
    if calibration is not None:
        files[f"calibration/{calibration.name}"] = read_user_file(calibration)
    if request.faults is not None:
        files[f"faults/{request.faults.name}"] = read_user_file(request.faults)
    return files
