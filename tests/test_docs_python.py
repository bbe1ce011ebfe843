"""The Python snippets of docs/*.md and README.md (issue 24: `PickGoal("red")` raised TypeError, a snippet used
an undefined `registry`), read top to bottom per file:
- every import statement runs (the names the docs import exist);
- every construction of a class imported from bt_grasp whose arguments are all literals is evaluated
  (``PickGoal("red")`` is a TypeError, ``PickGoal(kind="pick", color="red")`` a goal);
- a snippet with no ``...`` placeholder, that compiles and uses no name it does not define (ruff's F821) is
  executed whole (tree-format.md's loading example), with the repository as the working directory.
Sketches (``...`` placeholders, pseudo-code, a leaf needing the simulator) get the first two checks only.
"""

from __future__ import annotations

import ast
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

REPO = Path(__file__).resolve().parents[1]
DOCS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
RUFF = Path(sys.executable).with_name("ruff")


def _blocks(path: Path) -> list[tuple[int, str]]:
    text = path.read_text()
    return [(text[: m.start()].count("\n") + 2, m.group(1))
            for m in re.finditer(r"^```python\n(.*?)^```", text, re.S | re.M)]


SNIPPETS = [(path, line, code) for path in DOCS for line, code in _blocks(path)]


def _imports(code: str) -> list[ast.stmt]:
    try:
        tree = ast.parse(code)
    except SyntaxError:  # a sketch: take its import lines alone
        lines = [line for line in code.splitlines() if re.match(r"(from \S+ )?import ", line)]
        tree = ast.parse(_join_continued(lines, code))
    return [node for node in ast.walk(tree) if isinstance(node, ast.Import | ast.ImportFrom)]


def _join_continued(lines: list[str], code: str) -> str:
    """Import lines with their parenthesised continuation lines."""
    out: list[str] = []
    all_lines = code.splitlines()
    for first in lines:
        i = all_lines.index(first)
        chunk = [first]
        while chunk[-1].count("(") + sum(c.count("(") for c in chunk[:-1]) > sum(c.count(")") for c in chunk):
            i += 1
            chunk.append(all_lines[i])
        out.append("\n".join(chunk))
    return "\n".join(out)


def test_the_snippets_are_read() -> None:
    assert len(SNIPPETS) >= 8
    assert any(p.name == "episode-api.md" for p, _, _ in SNIPPETS)


@pytest.mark.parametrize(("path", "line", "code"), SNIPPETS, ids=[f"{p.name}:{n}" for p, n, _ in SNIPPETS])
def test_imports_and_literal_calls_of_every_snippet(path: Path, line: int, code: str) -> None:
    namespace: dict[str, Any] = {}
    for path_, _, earlier in SNIPPETS:  # a doc is read top to bottom: earlier snippets' imports count
        if path_ == path and earlier is not code:
            for node in _imports(earlier):
                exec(compile(ast.Module([node], []), str(path), "exec"), namespace)
        if earlier is code:
            break
    imported: set[str] = set()
    for node in _imports(code):
        exec(compile(ast.Module([node], []), f"{path}:{line}", "exec"), namespace)
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("bt_grasp"):
            imported |= {alias.asname or alias.name for alias in node.names}
    try:
        tree = ast.parse(code)
    except SyntaxError:
        return
    for call in (n for n in ast.walk(tree) if isinstance(n, ast.Call)):
        literal = all(isinstance(a, ast.Constant) for a in call.args) and all(
            isinstance(k.value, ast.Constant) and k.arg is not None for k in call.keywords)
        if (isinstance(call.func, ast.Name) and call.func.id in imported and isinstance(namespace[call.func.id], type)
                and literal and (call.args or call.keywords)):  # a value built from literals: no file, no effect
            text = ast.unparse(call)
            try:
                eval(compile(ast.Expression(call), f"{path}:{line}", "eval"), namespace)
            except Exception as exc:
                pytest.fail(f"{path.name}:{line + call.lineno - 1}: `{text}` raises {type(exc).__name__}: {exc}")


def _complete(code: str) -> bool:
    if "..." in code:
        return False
    try:
        ast.parse(code)
    except SyntaxError:
        return False
    check = subprocess.run([str(RUFF), "check", "--select", "F821", "--stdin-filename", "snippet.py", "-"],
                           input=code, capture_output=True, text=True, check=False)
    return check.returncode == 0


COMPLETE = [(p, n, c) for p, n, c in SNIPPETS if _complete(c)]
#: complete, and cheap: an episode needs the simulator and a user's leaf the user's tree (both tested elsewhere:
#: tests/plugins runs own-leaves.md's leaf file, the sim tests run episodes)
CHEAP = [(p, n, c) for p, n, c in COMPLETE if "run_episode(" not in c and "RobotLeaf" not in c]


def test_tree_format_loading_example_is_complete() -> None:
    """It used `registry`, defined nowhere: ruff's F821 would have kept it from running."""
    assert any(p.name == "tree-format.md" and "load_tree(" in c for p, _, c in COMPLETE)


@pytest.mark.parametrize(("path", "line", "code"), CHEAP, ids=[f"{p.name}:{n}" for p, n, _ in CHEAP])
def test_complete_snippets_run(path: Path, line: int, code: str) -> None:
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=300,
                          check=False)
    assert done.returncode == 0, f"{path.name}:{line}: {done.stderr[-2000:]}"
