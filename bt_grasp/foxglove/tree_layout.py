"""The Foxglove layout of the tree that ran: the shipped panels, with one State Transitions row per leaf of
*this* tree, labelled with the leaf's path (the node's one name: ``tree show``, replay, the report and the
campaign results show the same), read from ``/bt/tick.leaves.<leaf_key(path)>``.

A run attaches its layout to its log (:data:`LAYOUT_ATTACHMENT`, log format 3); ``replay --foxglove`` writes
it beside the log. For an older log the layout is made from the log's own tree and ``/bt/tick.leaves`` keys.
"""

from __future__ import annotations

import copy
import json
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from bt_grasp.files.json_types import JsonObject
from bt_grasp.files.output_files import write_output_file
from bt_grasp.foxglove.layout import layout_path, with_control_panels
from bt_grasp.recording import topics

if TYPE_CHECKING:
    from bt_grasp.recording.reader import RunLog
    from bt_grasp.tree.records import TreeNode

#: the attachment holding the run's layout
LAYOUT_ATTACHMENT = "foxglove/layout.json"
#: the shipped layout's State Transitions panel, whose rows are replaced by the tree's leaves
STATE_PANEL = "StateTransitions!leaves"
_LEAF_KINDS = ("Action", "Condition")


def _leaves(node: TreeNode) -> Iterator[TreeNode]:
    if node.get("kind") in _LEAF_KINDS:
        yield node
    for child in node.get("children", ()):
        yield from _leaves(child)


def leaf_paths(structure: TreeNode) -> list[str]:
    """The leaves' paths in tree order (uid order: the order of ``/bt/tick.leaves``)."""
    leaves = sorted(_leaves(structure), key=lambda n: int(n.get("uid", 0)))
    return [str(n.get("path") or n.get("name", "")) for n in leaves]


def tree_layout(rows: Sequence[tuple[str, str]], title: str = "") -> JsonObject:
    """The shipped layout with the State Transitions rows ``(label, key of /bt/tick.leaves)``."""
    layout: JsonObject = json.loads(layout_path().read_text())
    config = copy.deepcopy(layout["configById"])
    assert isinstance(config, dict)  # the shipped layout's panels by id
    shipped = config.get(STATE_PANEL, {})
    assert isinstance(shipped, dict)
    panel = dict(shipped)
    panel["paths"] = [{"value": f"{topics.TICK}.leaves.{key}", "timestampMethod": "receiveTime", "label": label}
                      for label, key in rows]
    if title:  # Foxglove shows it as the panel's title
        panel["foxglovePanelTitle"] = f"State Transitions: {title}"
    config[STATE_PANEL] = panel
    return {**layout, "configById": config}


def layout_for_structure(structure: TreeNode, title: str = "") -> JsonObject:
    """The layout for a tree as ``tree_structure`` gives it (what a run attaches to its log)."""
    paths = leaf_paths(structure)
    return tree_layout(list(zip(paths, topics.leaf_keys(paths), strict=True)), title)


def layout_bytes(structure: TreeNode, title: str = "") -> bytes:
    return (json.dumps(layout_for_structure(structure, title), indent=2) + "\n").encode()


def layout_for_log(run: RunLog) -> JsonObject:
    """The log's own layout (attached by the run), else one made from its tree and its leaves' keys."""
    attached = run.attachments.get(LAYOUT_ATTACHMENT)
    if attached is not None:
        try:
            value = json.loads(attached)
        except ValueError:
            value = None
        if isinstance(value, dict) and STATE_PANEL in value.get("configById", {}):
            layout: JsonObject = value
            return layout
    parents = {info.parent for info in run.nodes.values()}
    # a log of format 1 spells node kinds in lower case: a leaf is also a node that is nobody's parent
    leaves = [info for uid, info in sorted(run.nodes.items())
              if info.is_leaf or uid not in parents]
    keys: list[str] = []
    for msg in run.iter_messages(topics.TICK):
        found = msg.message.get("leaves") if isinstance(msg.message, dict) else None
        if isinstance(found, dict) and found:
            keys = [str(k) for k in found]
            break
    title = Path(str(run.metadata.get("tree_file", ""))).name
    if len(keys) == len(leaves):  # format 1 and 2 logs keyed their leaves by name: label them by path
        return tree_layout([(info.path or info.name, key) for info, key in zip(leaves, keys, strict=True)], title)
    paths = [info.path or info.name for info in leaves]
    return tree_layout(list(zip(paths, topics.leaf_keys(paths), strict=True)), title)


def write_layout(run: RunLog, target: Path | None = None) -> Path:
    """Write the log's layout to ``target`` (default ``<log>.layout.json`` beside the log); returns the file.
    A place that cannot be written is an ``InputError`` naming it."""
    target = target if target is not None else run.path.with_name(run.path.stem + ".layout.json")
    return write_output_file(target, json.dumps(layout_for_log(run), indent=2) + "\n", "--layout-out",
                             example="run.layout.json")


def layout_for_tree_file(tree: Path, leaves: Sequence[str] = ()) -> JsonObject:
    """The layout a run of this tree file attaches to its log (for a live view, before any log exists).
    ``leaves``: the ``--leaves`` plugins the tree needs."""
    # deferred: start-up time (the tree package and the leaf library, which replay --foxglove does not need)
    from bt_grasp.behaviours.library import robot_registry
    from bt_grasp.tree.introspect import tree_structure  # deferred: start-up time, as above
    from bt_grasp.tree.loader import load_tree  # deferred: start-up time, as above

    loaded = load_tree(tree, robot_registry(leaves))
    return layout_for_structure(tree_structure(loaded.root), Path(tree).name)


def write_live_layout(tree: Path, leaves: Sequence[str] = (), log: Path | None = None,
                      control: bool = False, folder: Path | None = None) -> Path:
    """Write the layout of ``tree`` for a live view (``control``: with the control panels of ``--control``)
    beside the run's log (``<log>.layout.json``) when it has one, else in ``folder`` (a private temporary folder
    the caller removes when the run ends: :func:`live_layout_folder`); returns the file."""
    if log is not None:
        target = log.with_name(log.stem + ".layout.json")
    elif folder is not None:
        target = Path(folder) / f"{Path(tree).stem}.layout.json"
    else:
        raise ValueError("a live layout without a log needs the folder it goes in")
    layout = layout_for_tree_file(tree, leaves)
    layout = with_control_panels(layout) if control else layout
    return write_output_file(target, json.dumps(layout, indent=2) + "\n", "--log")


def live_layout_folder(live: bool, log: Path | None) -> tempfile.TemporaryDirectory[str] | None:
    """The private temporary folder a live run without a log keeps its layout in, for the run's length (the
    caller cleans it up: found by the pre-review attack, every such run left a folder behind); None otherwise."""
    return tempfile.TemporaryDirectory(prefix="bt_grasp_layout_") if live and log is None else None
