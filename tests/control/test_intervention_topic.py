"""/control/interventions: registered with the first intervention only, read back, listed by replay and the run
report; a malformed recorded intervention is one sentence for ``replay --resim``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from mcap.reader import make_reader

from bt_grasp.cli.resim import _interventions
from bt_grasp.control import InterventionRecord
from bt_grasp.errors import LogFileError
from bt_grasp.recording import topics
from bt_grasp.recording.interventions import interventions_html, interventions_table
from bt_grasp.recording.reader import open_log
from bt_grasp.recording.writer import RunRecorder

RECORD = InterventionRecord(12, 110_000_000, "terminal", {"kind": "set_blackboard", "key": "lift_height",
                                                            "value": 0.12}, "lift_height = 0.12")


def _log(path: Path, records: list[InterventionRecord]) -> None:
    recorder = RunRecorder(path, metadata={"seed": "0"}, handle_signals=False)
    recorder.write_tick(1, 0, [{"uid": 1, "path": "a", "name": "a", "type": "A", "status": "RUNNING"}], {})
    for record in records:
        recorder.write_intervention(record.stamp_ns, record.to_json())
    recorder.write_tick(2, 10_000_000, [{"uid": 1, "status": "SUCCESS"}], {})
    recorder.close()


def _channels(path: Path) -> dict[str, tuple[str, str, bytes]]:
    with path.open("rb") as f:
        summary = make_reader(f).get_summary()
    assert summary is not None
    return {c.topic: (c.message_encoding, summary.schemas[c.schema_id].name, summary.schemas[c.schema_id].data)
            for c in summary.channels.values()}


def test_the_channel_exists_only_when_something_was_done(tmp_path: Path) -> None:
    _log(tmp_path / "none.mcap", [])
    _log(tmp_path / "one.mcap", [RECORD, RECORD])
    none, one = _channels(tmp_path / "none.mcap"), _channels(tmp_path / "one.mcap")
    assert topics.INTERVENTIONS not in none
    assert set(one) - set(none) == {topics.INTERVENTIONS}
    encoding, schema, data = one[topics.INTERVENTIONS]
    assert (encoding, schema) == ("json", "bt_grasp.Intervention")
    assert json.loads(data) == topics.JSON_SCHEMAS[topics.INTERVENTIONS]
    run = open_log(tmp_path / "one.mcap")
    assert [InterventionRecord.from_json(r) for r in run.interventions] == [RECORD, RECORD]
    assert open_log(tmp_path / "none.mcap").interventions == []


def test_the_schema_is_one_foxglove_reads() -> None:
    # Foxglove 1.48's JSON-schema subset (PLATFORM-NOTES): one type per property, enum only with a type, every
    # object with properties
    def check(node: dict[str, Any]) -> None:
        assert isinstance(node.get("type"), str)
        if "enum" in node:
            assert node["type"] == "string"
        if node["type"] == "object":
            assert "properties" in node
            for child in node["properties"].values():
                check(child)

    check(topics.JSON_SCHEMAS[topics.INTERVENTIONS])


def test_replay_lists_them_and_the_report_marks_them() -> None:
    from rich.console import Console

    console = Console(width=160, record=True)
    console.print(interventions_table([{**RECORD.to_json()}]))
    text = console.export_text()
    assert "interventions (1)" in text
    assert "0.110" in text and "12" in text and "terminal" in text and "set_blackboard" in text
    assert '"key": "lift_height"' in text and "lift_height = 0.12" in text
    page = interventions_html([{**RECORD.to_json(), "effect": "<b>x</b>"}])
    assert "Operator interventions" in page and "&lt;b&gt;x&lt;/b&gt;" in page
    assert interventions_html([]) == ""


@pytest.mark.parametrize(
    ("record", "words"),
    [
        ({"tick": 1, "source": "terminal"}, "'command'"),
        ({"tick": "one", "command": {"kind": "stop"}}, "invalid literal"),
        ({"tick": 1, "command": {"kind": "jump"}}, "unknown command kind 'jump'"),
        ({"tick": 1, "command": {"kind": "set_blackboard", "key": "k", "value": {"a": 1}}}, "needs 'value'"),
    ],
)
def test_a_malformed_recorded_intervention_is_one_sentence(record: dict[str, Any], words: str) -> None:
    with pytest.raises(LogFileError) as info:
        _interventions(Path("run.mcap"), [record])
    message = info.value.message
    assert message.startswith("run.mcap: intervention 0 on /control/interventions cannot be applied again: ")
    assert words in message and "\n" not in message
