"""Draw a built tree: a rich ``Tree`` for the terminal, Graphviz dot text, or png/svg through ``dot``."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

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


def _label(node: BtNode) -> str:
    title = node.bt_type if node.name == node.bt_type else f"{node.bt_type} {node.name!r}"
    if node.bt_type == "SubTree":
        title = f"SubTree {getattr(node, 'subtree_id', '')}" + (f" {node.name!r}" if node.name != getattr(
            node, "subtree_id", "") else "")  # fmt: skip
    ports = [f"{k}={v}" for k, v in node.bt_attributes.items() if k != "name"]
    return title + (f" ({', '.join(ports)})" if ports else "")


def rich_tree(root: BtNode, *, with_status: bool = False) -> rich.tree.Tree:
    def add(node: BtNode, parent: rich.tree.Tree | None) -> rich.tree.Tree:
        # the node's one name, its path (BT.CPP's fullPath), as replay, the report and Foxglove show it
        text = (f"[{_STYLE[node.bt_kind]}]{rich.markup.escape(_label(node))}[/] [dim]#{node.bt_uid} "
                f"{rich.markup.escape(node.bt_path)}[/]")
        if with_status:
            text += f" [bold]{bt_status_name(node)}[/]"
        branch = rich.tree.Tree(text) if parent is None else parent.add(text)
        for child in node.children:
            add(child, branch)  # type: ignore[arg-type]
        return branch

    return add(root, None)


def _quote(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def to_dot(root: BtNode, title: str = "tree") -> str:
    lines = [f"digraph {_quote(title)} {{", "  node [fontname=Helvetica, fontsize=11];"]

    def add(node: BtNode) -> None:
        label = _quote(_label(node))[:-1] + "\\n" + _quote(f"{node.bt_path} #{node.bt_uid}")[1:]
        lines.append(f"  n{node.bt_uid} [label={label}, shape={_SHAPE[node.bt_kind]}];")
        for child in node.children:
            lines.append(f"  n{node.bt_uid} -> n{child.bt_uid};")  # type: ignore[attr-defined]
            add(child)  # type: ignore[arg-type]

    add(root)
    lines.append("}")
    return "\n".join(lines) + "\n"


def render_image(dot_text: str, fmt: str, out: Path) -> None:
    """Run Graphviz ``dot`` to write ``out`` as png or svg."""
    dot = shutil.which("dot")
    if dot is None:
        raise InputError(f"--format {fmt}", "Graphviz 'dot' is not installed; install graphviz or use --format dot")
    result = subprocess.run(
        [dot, f"-T{fmt}", "-o", str(out)], input=dot_text, text=True, capture_output=True, check=False
    )
    if result.returncode != 0:
        raise InputError(f"--format {fmt}", f"dot failed: {result.stderr.strip().splitlines()[-1:]}")
