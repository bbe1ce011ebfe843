"""What a log records about the run that made it: inputs, versions, commit (enough to run it again)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from bt_grasp.episode.request import EpisodeRequest
from bt_grasp.episode.result import goal_json
from bt_grasp.errors import InputError
from bt_grasp.files.bounded_io import read_user_file
from bt_grasp.files.safe_path import check_relative_name
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
    meta = {
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
    links = tree_include_links(tree)
    if links:  # where each include was found, so that `replay --resim` reads the log's own copy of each
        meta["tree_includes"] = json.dumps(links)
    return meta


def tree_attachment_names(tree: LoadedTree) -> dict[str, str]:
    """Each tree file's attachment name, by its path as displayed: the main tree ``tree/<its name>``; an included
    file the path its include wrote, from the including file's attachment folder (``tree/lib/pick.xml``, wherever
    it was found: beside, on ``BT_GRASP_TREE_PATH`` or in the shipped library); an include written with an
    absolute path or ``..`` out of ``tree/``, or a name another file took, ``tree/include-N/<its name>``."""
    main = tree.document.source
    names = {main: f"tree/{Path(main).name}"}
    taken = set(names.values())
    for link in tree.document.include_links:
        if link.resolved in names:
            continue
        name = ""
        if not os.path.isabs(link.path):
            name = os.path.normpath(os.path.join(os.path.dirname(names[link.source]), link.path))
            try:
                check_relative_name(name, source=link.source)
            except InputError:
                name = ""
        if not name.startswith("tree/") or name in taken:
            name = f"tree/include-{len(taken)}/{Path(link.resolved).name}"
        names[link.resolved] = name
        taken.add(name)
    return names


def tree_include_links(tree: LoadedTree) -> list[list[str]]:
    """Every include of the run as ``[including file's attachment, path as written, included file's attachment]``
    (the run metadata ``tree_includes``: ``replay --resim`` resolves each include to the log's own file)."""
    names = tree_attachment_names(tree)
    return [[names[link.source], link.path, names[link.resolved]] for link in tree.document.include_links]


def run_attachments(request: EpisodeRequest, tree: LoadedTree, calibration: Path | None) -> dict[str, bytes]:
    """The exact bytes of every input file (``replay --resim`` runs them again)."""
    files: dict[str, bytes] = {}
    names = tree_attachment_names(tree)
    for name, text in tree.sources.items():
        files[names.get(name, f"tree/{Path(name).name}")] = text.encode()
    files[f"scene/{request.scene.name}"] = read_user_file(request.scene)  # bounded, as when they were loaded
    if calibration is not None:
        files[f"calibration/{calibration.name}"] = read_user_file(calibration)
    if request.faults is not None:
        files[f"faults/{request.faults.name}"] = read_user_file(request.faults)
    return files
