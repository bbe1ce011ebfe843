"""Draw a built tree: a rich ``Tree`` for the terminal, Graphviz dot text, or png/svg through ``dot``."""

from __future__ import annotations

import shutil
import subprocess

import rich.tree

from bt_grasp.errors import InputError
from bt_grasp.tree.introspect import bt_status_name
from bt_grasp.tree.node import BtNode
from bt_grasp.tree.registry import NodeKind

_STYLE = {
    NodeKind.CONTROL: "bold cyan",
    NodeKind.DECORATOR: "magenta",
    NodeKind.ACTION: "green",
    NodeKind.CONDITION: "yellow",
    NodeKind.SUBTREE: "bold blue",
}
_SHAPE = {
    NodeKind.CONTROL: "box",
    NodeKind.DECORATOR: "hexagon",
    NodeKind.ACTION: "ellipse",
    NodeKind.CONDITION: "diamond",
    NodeKind.SUBTREE: "folder",
}


def _title(node: BtNode) -> str:
    title = node.bt_type if node.name == node.bt_type else f"{node.bt_type} {node.name!r}"
    if node.bt_type == "SubTree":
        title = f"SubTree {getattr(node, 'subtree_id', '')}" + (f" {node.name!r}" if node.name != getattr(
            node, "subtree_id", "") else "")  # fmt: skip
    return title


def _ports(node: BtNode) -> list[str]:
    return [f"{k}={v}" for k, v in node.bt_attributes.items() if k != "name"]


def _label(node: BtNode) -> str:
    ports = _ports(node)
    return _title(node) + (f" ({', '.join(ports)})" if ports else "")


def rich_tree(root: BtNode, *, with_status: bool = False) -> rich.tree.Tree:
    def add(node: BtNode, parent: rich.tree.Tree | None) -> rich.tree.Tree:
        # the node's one name, its path (BT.CPP's fullPath), as replay, the report and Foxglove show it
        text = (f"[{_STYLE[node.bt_kind]}]{rich.markup.escape(_label(node))}[/] [dim]#{node.bt_uid} "
                f"{rich.markup.escape(node.bt_path)}[/]")
        if with_status:
            text += f" [bold]{bt_status_name(node)}[/]"
        branch = rich.tree.Tree(text) if parent is None else parent.add(text)
        for child in node.bt_children():
            add(child, branch)
        return branch

    return add(root, None)


def _quote(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


#: fill colours of the picture, by node kind (as Groot2 tells kinds apart) and, with statuses, by status
KIND_FILL = {
    NodeKind.CONTROL: "#cfe2f3",
    NodeKind.DECORATOR: "#ead1dc",
    NodeKind.ACTION: "#d9ead3",
    NodeKind.CONDITION: "#fff2cc",
    NodeKind.SUBTREE: "#d0e0e3",
}
STATUS_FILL = {"SUCCESS": "#93c47d", "FAILURE": "#e06666", "RUNNING": "#f6b26b", "IDLE": "#eeeeee",
               "INVALID": "#eeeeee"}


def to_dot(root: BtNode, title: str = "tree", *, with_status: bool = False) -> str:
    """Graphviz dot of the tree, drawn left to right (a wide tree is a tall picture that stays readable: its
    depth runs across, its siblings down), filled by node kind, or by status with ``with_status``, legend
    included."""
    lines = [
        f"digraph {_quote(title)} {{",
        "  rankdir=LR; nodesep=0.12; ranksep=0.35;",
        '  node [fontname=Helvetica, fontsize=11, style="filled,rounded", color="#666666"];',
        '  edge [color="#888888", arrowsize=0.6];',
    ]

    def add(node: BtNode) -> None:
        # one line each: the title, every port, the node's path and uid (and its status): narrow boxes
        parts = [_title(node), *_ports(node), f"{node.bt_path} #{node.bt_uid}"]
        fill = KIND_FILL[node.bt_kind]
        if with_status:
            status = bt_status_name(node)
            parts.append(status)
            fill = STATUS_FILL.get(status, fill)
        label = '"' + "\\n".join(_quote(part)[1:-1] for part in parts) + '"'
        lines.append(f'  n{node.bt_uid} [label={label}, shape={_SHAPE[node.bt_kind]}, fillcolor="{fill}"];')
        for child in node.bt_children():
            lines.append(f"  n{node.bt_uid} -> n{child.bt_uid};")
            add(child)

    add(root)
    legend = STATUS_FILL if with_status else {kind.value: fill for kind, fill in KIND_FILL.items()}
    lines.append('  subgraph cluster_legend { label="legend"; fontname=Helvetica; fontsize=10; color="#bbbbbb";')
    lines.extend(f'    legend_{i} [label={_quote(str(name).lower())}, shape=box, fontsize=9, fillcolor="{fill}"];'
                 for i, (name, fill) in enumerate(legend.items()) if name != "INVALID")
    lines.append("  }")
    lines.append("}")
    return "\n".join(lines) + "\n"


def render_image(dot_text: str, fmt: str) -> bytes:
    """The tree drawn by Graphviz ``dot`` as png or svg bytes (the caller writes them where the user said)."""
    dot = shutil.which("dot")
    if dot is None:
        raise InputError(f"--format {fmt}", "Graphviz 'dot' is not installed; install graphviz or use --format dot")
    result = subprocess.run([dot, f"-T{fmt}"], input=dot_text.encode("utf-8"), capture_output=True, check=False)
    if result.returncode != 0:
        last = result.stderr.decode("utf-8", "replace").strip().splitlines()[-1:]
        raise InputError(f"--format {fmt}", f"dot failed: {last}")
    return result.stdout
