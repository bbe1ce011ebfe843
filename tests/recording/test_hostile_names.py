"""Issue 22, item 4 and the weak item "bad log contents giving tracebacks", found by the pre-review attack:
`replay LOG --leaf NAME` with Rich markup in the name was a MarkupError traceback (a table title parsed the
name as markup), and paths printed by replay were markup too (`--report '[b]x[/].html'` printed `x.html`).
Here every free-form string of a log (node names and paths, feedback, failure reasons, blackboard keys and
values, event and fault fields, trajectory names) carries markup, HTML and mathtext, and every view of `replay`
must show it as text, in one piece, with no traceback."""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

REPO = Path(__file__).resolve().parents[2]
SEED_LOG = REPO / "tests/data/old_logs/format1.mcap"
BT = [sys.executable, "-m", "bt_grasp.cli.main"]
#: Rich markup, a link, HTML, matplotlib mathtext and a path step, all at once
HOSTILE = "[/]<b>$x^$[link=https://x.invalid]..[/link]"
#: values that say what a log's structure means, and node types (registry names: a bt_grasp log's types are never
#: a user's text): kept as they are
STRUCTURAL = frozenset({"status", "kind", "__type__", "encoding", "frame_id", "type"})


def _taint(value: Any, key: str = "", keep: frozenset[str] = STRUCTURAL, suffix: str = HOSTILE) -> Any:
    if isinstance(value, str):
        return value if key in keep or not value else value + suffix
    if isinstance(value, list):
        return [_taint(v, key, keep, suffix) for v in value]
    if isinstance(value, dict):
        return {(k + suffix if key == "bb" else k): _taint(v, k, keep, suffix) for k, v in value.items()}
    return value


def _hostile_log(path: Path, keep: frozenset[str] = STRUCTURAL, meta: dict[str, str] | None = None,
                 suffix: str = HOSTILE) -> Path:
    from mcap.reader import make_reader
    from mcap.writer import Writer

    reader = make_reader(io.BytesIO(SEED_LOG.read_bytes()))
    with path.open("wb") as out:
        writer = Writer(out)
        writer.start(profile="", library="test")
        schemas: dict[int, int] = {}
        channels: dict[int, int] = {}
        for schema, channel, message in reader.iter_messages():
            if schema is not None and schema.id not in schemas:
                schemas[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
            if channel.id not in channels:
                channels[channel.id] = writer.register_channel(channel.topic, channel.message_encoding,
                                                               schemas.get(channel.schema_id, 0))
            data = message.data
            if channel.message_encoding == "json" and channel.topic != "/robot/joint_state":
                data = json.dumps(_taint(json.loads(data), keep=keep, suffix=suffix)).encode()
            writer.add_message(channels[channel.id], message.log_time, data, message.publish_time)
        for record in reader.iter_metadata():
            values = dict(record.metadata)
            if "scene" in values:
                values["scene"] += suffix
            writer.add_metadata(record.name, {**values, **(meta or {})})
        writer.finish()
    return path


@pytest.fixture(scope="module")
def hostile_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _hostile_log(tmp_path_factory.mktemp("hostile") / f"run{HOSTILE.replace('/', '_')}.mcap")


VIEWS = {
    "summary": [],
    "tick": ["--tick", "5"],
    "failures": ["--failures"],
    "leaf": ["--leaf", "Grasp" + HOSTILE],
    "json": ["--json"],
    "topic": ["--topic", "/bt/events"],
    "report": ["--report", "report.html"],
    "foxglove": ["--foxglove", "--layout-out", "layout.json"],
    "btlog": ["--export-btlog", "run.btlog"],
}


@pytest.mark.parametrize("view", sorted(VIEWS))
def test_item4_every_replay_view_shows_markup_from_a_log_as_text(view: str, hostile_log: Path,
                                                                  tmp_path: Path) -> None:
    proc = subprocess.run([*BT, "replay", str(hostile_log), *VIEWS[view]], capture_output=True, text=True,
                          timeout=240, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "Traceback" not in proc.stderr and proc.stderr.strip() == "", proc.stderr[-3000:]
    if view in ("summary", "tick", "failures", "leaf"):
        assert HOSTILE in proc.stdout.replace("\n", ""), proc.stdout[-3000:]
    if view == "report":
        page = (tmp_path / "report.html").read_text()
        assert "<b>$x^$" not in page and "&lt;b&gt;" in page  # escaped, never markup


def test_weak_item_a_btlog_export_of_a_type_xml_cannot_carry_names_the_log_and_writes_nothing(tmp_path: Path) -> None:
    from bt_grasp.errors import LogFileError
    from bt_grasp.recording.btlog import write_btlog
    from bt_grasp.recording.reader import open_log

    log = _hostile_log(tmp_path / "typed.mcap", keep=STRUCTURAL - {"type"})  # node types with markup: no XML names
    with pytest.raises(LogFileError, match=r"typed\.mcap: cannot be exported as \.btlog: its tree holds a node type"):
        write_btlog(open_log(log), tmp_path / "out.btlog")
    assert not (tmp_path / "out.btlog").exists()  # before: a .btlog of XML no parser reads, then the refusal


def test_item4_the_leaf_view_names_the_leaf_as_given(hostile_log: Path, tmp_path: Path) -> None:
    proc = subprocess.run([*BT, "replay", str(hostile_log), "--leaf", "Grasp" + HOSTILE], capture_output=True,
                          text=True, timeout=240, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert f"history of Grasp{HOSTILE}" in proc.stdout.replace("\n", ""), proc.stdout


@pytest.mark.parametrize(("meta", "fragment"), [({"start_unix_ns": "abc"}, "'start_unix_ns' is 'abc'"),
                                                ({"start_unix_ns": "9" * 400}, "not a time")])
def test_weak_item_a_btlog_export_with_bad_run_metadata_is_one_sentence(meta: dict[str, str], fragment: str,
                                                                        tmp_path: Path) -> None:
    log = _hostile_log(tmp_path / "meta.mcap", meta=meta)
    proc = subprocess.run([*BT, "replay", str(log), "--export-btlog", "out.btlog"], capture_output=True, text=True,
                          timeout=240, cwd=tmp_path)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr[-2000:]
    assert fragment in proc.stderr and "meta.mcap" in proc.stderr and not (tmp_path / "out.btlog").exists()


#: clear the screen, retitle the window (terminated by ST, which Rich keeps), red text, a right-to-left override
TERMINAL = "\x1b[2J\x1b]0;owned\x1b\\\x1b[31m\u202e"


@pytest.mark.parametrize("view", ["summary", "tick", "failures", "leaf"])
def test_weak_item_terminal_control_sequences_in_a_log_are_shown_not_obeyed(view: str, tmp_path: Path) -> None:
    """Found by the pre-review attack: Rich escapes markup but passes ESC through, so a log's node name could
    clear the screen, retitle the window or colour the rest of the output of `replay`."""
    log = _hostile_log(tmp_path / "esc.mcap", suffix=TERMINAL)
    from bt_grasp.files.terminal_text import shown

    leaf = shown("Grasp" + TERMINAL)  # as every view shows it: the name a user can type
    args = {"summary": [], "tick": ["--tick", "5"], "failures": ["--failures"], "leaf": ["--leaf", leaf]}[view]
    proc = subprocess.run([*BT, "replay", str(log), *args], capture_output=True, text=True, timeout=240,
                          cwd=tmp_path, env={**os.environ, "TERM": "xterm-256color", "FORCE_COLOR": "1"})
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "\\x1b[2J" in proc.stdout and "\\u202e" in proc.stdout, proc.stdout[-2000:]
    assert "\x1b[2J" not in proc.stdout and "\x1b]0;" not in proc.stdout and "\u202e" not in proc.stdout
