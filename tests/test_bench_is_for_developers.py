"""One evaluation entry point (issue 24, done-when 5): `eval run` evaluates; every `bench` command is a developer
benchmark, in one of two `bench --help` panels (episode benchmarks, micro-benchmarks), and docs/campaigns.md says
for each why it is not an entry point. On main as it was `bench --help` listed the ten commands in one panel, the
episode benchmark `bench eval` did not say it was one, and the docs named the commands in a sentence, with no
reason per command and nothing holding the list to the group."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from bt_grasp.cli.main import main

REPO = Path(__file__).resolve().parents[1]
KINDS = {"episode benchmark": "Episode benchmarks", "micro-benchmark": "Micro-benchmarks"}


def _docs_table() -> dict[str, str]:
    """docs/campaigns.md's table: bench command -> kind."""
    text = (REPO / "docs/campaigns.md").read_text()
    section = text[text.index("### Why each `bench` command is not an evaluation entry point"):]
    rows = re.findall(r"^\| `bench ([\w-]+)` \| ([\w -]+) \|", section, re.M)
    return {name: kind.strip() for name, kind in rows}


def _bench_commands() -> dict[str, str | None]:
    """The bench group's commands and the --help panel each is in."""
    import typer
    from typer.main import get_command

    from bt_grasp.cli import bench_cell_cmd, bench_cmd, bench_eval_cmd, bench_extra_cmd

    app = typer.Typer()
    for module in (bench_extra_cmd, bench_cmd, bench_eval_cmd, bench_cell_cmd):
        module.register(app)
    group = get_command(app).commands["bench"]  # type: ignore[attr-defined]
    return {name: getattr(command, "rich_help_panel", None) for name, command in group.commands.items()}


def test_the_docs_give_every_bench_command_its_kind_and_it_sits_in_that_panel() -> None:
    table = _docs_table()
    commands = _bench_commands()
    assert sorted(table) == sorted(commands)  # a new bench command must be listed (and a gone one unlisted)
    assert set(table.values()) <= set(KINDS), table
    for name, kind in table.items():
        panel = commands[name]
        assert panel is not None and panel.startswith(KINDS[kind]), (name, kind, panel)
    assert {n for n, k in table.items() if k == "episode benchmark"} == {"pick", "tasks", "eval", "twin"}


def test_bench_help_shows_the_two_panels_and_the_entry_point(capsys: pytest.CaptureFixture[str],
                                                             monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("COLUMNS", "200")
    assert main(["bench", "--help"]) == 0
    out = capsys.readouterr().out
    assert "Developer benchmarks" in out and "eval run --tree T --scene S --seeds N" in out
    episodes = out.index("Episode benchmarks (developer; to evaluate a tree: eval run --tree T --scene S --seeds N)")
    micro = out.index("Micro-benchmarks (developer")
    for name in ("pick", "tasks", "eval"):  # under the episode panel's title, in the panel it opens
        assert re.search(rf"^│ {name} ", out[episodes:], re.M), name
        assert not re.search(rf"^│ {name} ", out[micro:episodes] if micro < episodes else out[micro:], re.M), name


@pytest.mark.parametrize("name", ["pick", "tasks", "eval"])
def test_each_episode_benchmark_says_it_is_one_and_names_eval_run(
    name: str, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "200")
    assert main(["bench", name, "--help"]) == 0
    text = " ".join(capsys.readouterr().out.replace("│", " ").split())
    assert "developer benchmark" in text.lower() and "bt-grasp eval run --tree" in text, text[:400]
