"""Every `bt-grasp` command in a code block of README.md and docs/*.md is checked against the CLI (issue 24:
the docs drifted from the code), so the docs cannot drift again.

What is done with each command line (``$ `` prompts, ``\\`` continuations and ``# comments`` handled):
- every one is *parsed* by the real command: its words name a command, and its options and values pass that
  command's own parser (types, choices, required arguments, unknown options), without running it. Optional
  groups ``[--format text|dot|png|svg]`` are checked twice: left out, and put in with the first alternative.
- the cheap ones whose files all exist in the repository are also *run* (through ``main``, exit 0 expected):
  ``tree validate``, ``tree show``, ``tree models``, ``tree run --dry`` and ``scene validate``. Commands that
  need the simulator, a cluster or the user's own files (``run``, ``eval``, ``calibrate``, ``replay`` of a
  log the reader made, ``my_leaves.py``, a package ``--plugin NAME`` the reader installed...) are parsed only.
"""

from __future__ import annotations

import itertools
import re
import shlex
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from bt_grasp.cli import main as cli

REPO = Path(__file__).resolve().parents[1]
DOCS = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
CHEAP = {("tree", "validate"), ("tree", "show"), ("tree", "models"), ("tree", "run"), ("scene", "validate")}


@dataclass(frozen=True)
class DocCommand:
    where: str  # file:line
    text: str  # as written (continuations joined, comment removed)

    def variants(self) -> list[list[str]]:
        """The argument lists to check: optional groups left out, then each put in (first alternative)."""
        groups = re.findall(r"\[([^\[\]]*)\]", self.text)
        base = re.sub(r"\s*\[[^\[\]]*\]", "", self.text)
        out = [[_sample(w) for w in shlex.split(base)[1:]]]
        for group in groups:
            words = [_sample(w.split("|")[0]) for w in shlex.split(group.replace("...", "")) if w]
            out.append(out[0] + words)
        return out


#: placeholders the docs write for a number (``--random SEED``, ``--max-ticks N``): parsed as a number
NUMBER_PLACEHOLDERS = {"N", "SEED", "PORT", "FACTOR", "S", "F"}


def _placeholder(word: str) -> bool:
    """FILE, IN.xml, NAME=OUTCOME: a word the reader replaces (a command holding one is parsed, not run)."""
    return re.fullmatch(r"[A-Z][A-Z_]*(\.\w+|=[A-Z_]+)?", word) is not None


def _sample(word: str) -> str:
    return "1" if word in NUMBER_PLACEHOLDERS else word


def doc_commands() -> list[DocCommand]:
    found: list[DocCommand] = []
    for path in DOCS:
        lines = path.read_text().splitlines()
        in_block = False
        pending = ""
        start = 0
        for number, line in enumerate(lines, 1):
            if line.lstrip().startswith("```"):
                in_block = not in_block
                continue
            if not in_block:
                continue
            text = line.strip().removeprefix("$ ")
            if pending:
                text = pending + " " + text
            elif text.startswith("bt-grasp "):
                start = number
            else:
                continue
            if text.endswith("\\"):
                pending = text[:-1].strip()
                continue
            pending = ""
            text = re.split(r"\s{2,}#|\s#\s", text, maxsplit=1)[0].strip()
            found.append(DocCommand(f"{path.relative_to(REPO)}:{start}", text))
    return found


COMMANDS = doc_commands()


def _resolve(args: list[str]) -> tuple[Any, list[str], list[str]]:
    """(click command, its words, its remaining arguments)."""
    from typer.main import get_command

    command = get_command(cli.build_app(cli.modules_for([])))  # every command (main builds only the named one's)
    words: list[str] = []
    while args and hasattr(command, "commands") and args[0] in command.commands:
        words.append(args[0])
        command = command.commands[args.pop(0)]
    return command, words, args


def test_the_docs_are_read() -> None:
    """The reader finds the commands the docs show today (one that found none would make the rest vacuous)."""
    assert len(COMMANDS) >= 25
    texts = [c.text for c in COMMANDS]
    assert any(t.startswith("bt-grasp detector dataset --scenes") and "--images 4" in t for t in texts)  # a `\`
    assert "bt-grasp tree convert IN.xml OUT.yaml" in texts  # the comment after it is gone
    ran = [c for c in COMMANDS if _runnable(c.variants()[0])]
    assert len(ran) >= 1, [c.text for c in ran]


@pytest.mark.parametrize("doc", COMMANDS, ids=[c.where for c in COMMANDS])
def test_every_docs_command_parses(doc: DocCommand) -> None:
    for args in doc.variants():
        if args[:1] == ["run"]:
            from bt_grasp.cli.run_cmd import fill_optional_values

            args = fill_optional_values(args)
        command, words, rest = _resolve(list(args))
        assert words, f"{doc.where}: `{doc.text}` names no bt-grasp command"
        assert not hasattr(command, "commands"), f"{doc.where}: `{doc.text}` names a group, not a command"
        try:
            command.make_context(" ".join(["bt-grasp", *words]), rest)
        except Exception as exc:  # click's errors (typer vendors click: matched by shape)
            fmt = getattr(exc, "format_message", None)
            if not callable(fmt):
                raise
            pytest.fail(f"{doc.where}: `{' '.join(['bt-grasp', *args])}` does not parse: {fmt()}")


def _runnable(args: list[str]) -> bool:
    words = tuple(args[:2])
    files = [a for a in args[2:] if not a.startswith("-") and re.search(r"\.(xml|yaml|yml|py)$", a)]
    return words in CHEAP and ("--dry" in args or words != ("tree", "run")) and "--out" not in args and all(
        (REPO / f).is_file() for f in files
    ) and not any(_placeholder(a) for a in args) and "--plugin" not in args  # --plugin: one the reader installed


@pytest.mark.parametrize(
    "doc", [c for c in COMMANDS if _runnable(c.variants()[0])], ids=lambda c: c.where
)
def test_cheap_docs_commands_run(doc: DocCommand, monkeypatch: pytest.MonkeyPatch,
                                 capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.chdir(REPO)
    for args in doc.variants():
        if not _runnable(args):
            continue
        code = cli.main(list(args))
        captured = capsys.readouterr()
        assert code == 0, f"{doc.where}: `bt-grasp {' '.join(args)}` exited {code}: {captured.err}"


#: commands the docs name on purpose as not existing (docs/testing.md's mutation table: a README row with no test)
MADE_UP = {"bt-grasp bench frobnicate"}


def inline_mentions() -> list[DocCommand]:
    """Every `bt-grasp ...` code span in the prose and tables (code blocks left out: checked above)."""
    found: list[DocCommand] = []
    for path in DOCS:
        text = re.sub(r"^```.*?^```", lambda m: "\n" * m.group(0).count("\n"), path.read_text(), flags=re.S | re.M)
        for match in re.finditer(r"`(bt-grasp [^`]+)`", text):
            if text[max(0, match.start() - 3): match.start()] == "no ":  # "no `bt-grasp detector train` yet"
                continue
            if match.group(1) in MADE_UP:
                continue
            line = text[: match.start()].count("\n") + 1
            found.append(DocCommand(f"{path.relative_to(REPO)}:{line}", match.group(1).replace("\\|", "|")))
    return found


MENTIONS = inline_mentions()


def test_every_inline_mention_names_a_command_and_its_options() -> None:
    """A mention in prose (`bt-grasp replay LOG --resim`) is no whole command line, so it is not parsed; its
    words must still name a command or group (alternatives such as `plan|perception` each), and every --option it
    shows must be one of that command's options."""
    assert len(MENTIONS) >= 100
    problems: list[str] = []
    for doc in MENTIONS:
        words = doc.text.split()[1:]
        head = [w for w in words if re.fullmatch(r"[a-z][a-z-]*(\|[a-z][a-z-]*)*", w)]
        lead = words[: next((i for i, w in enumerate(words) if w not in head), len(words))]
        alternatives = [w.split("|") for w in lead]
        for choice in (list(c) for c in itertools.product(*alternatives)):
            command, named, _ = _resolve(list(choice))
            if (not named and not (words and words[0].startswith("--"))) or (
                    hasattr(command, "commands") and len(named) < len(choice)):  # a group, then no command of it
                problems.append(f"{doc.where}: `{doc.text}` names no command ({' '.join(choice)})")
                continue
            known = {o for p in command.params for o in (*p.opts, *p.secondary_opts)} | {"--help"}
            problems += [f"{doc.where}: `{doc.text}`: bt-grasp {' '.join(named)} has no option {option}"
                         for option in re.findall(r"(?<![\w-])--[a-z][\w-]*", doc.text) if option not in known]
    assert not problems, "\n".join(problems)
