"""`--leaves` on the commands that run trees on the simulator (`run`, `eval run`, `replay --resim`): the plugin's
nodes pass every input check before anything starts, and a bad plugin stops the command with exit 2 and one
sentence before any world is built (no simulator needed here; tests/plugins/test_example_package.py runs one)."""

from __future__ import annotations

from pathlib import Path

import pytest

from bt_grasp.campaign.spec import load_campaign
from bt_grasp.cli.main import main

REPO = Path(__file__).resolve().parents[2]
PLUGIN = Path(__file__).parent / "data" / "user_nodes.py"
SCENE = REPO / "scenes" / "tabletop.yaml"

TREE = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence>
      <Fallback><CheckWeight grams="750"/><FailureIs reason="WEIGHT_OUT_OF_RANGE"/></Fallback>
      <OpenGripper/>
    </Sequence>
  </BehaviorTree>
</root>
"""


@pytest.fixture
def campaign_file(tmp_path: Path) -> Path:
    (tmp_path / "weigh.xml").write_text(TREE)
    path = tmp_path / "weigh.yaml"
    path.write_text(f"name: weigh\ntrees: [weigh.xml]\nscenes: [{SCENE}]\nseeds: [0, 1]\n")
    return path


def test_campaign_checks_and_episodes_carry_the_leaves(campaign_file: Path) -> None:
    campaign = load_campaign(campaign_file, leaves=(str(PLUGIN),))
    assert [e.request.leaves for e in campaign.episodes()] == [(str(PLUGIN),), (str(PLUGIN),)]


def test_eval_run_without_the_plugin_names_the_campaign_and_node(
    campaign_file: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["eval", "run", str(campaign_file), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert str(campaign_file) in err and "unknown node 'CheckWeight'" in err


def test_eval_run_with_a_bad_plugin_names_it(campaign_file: Path, tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "bad.py"
    bad.write_text("import no_such_module_for_bt_grasp\n")
    assert main(["eval", "run", str(campaign_file), "--out", str(tmp_path / "out"), "--leaves", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert f"{bad}:1: import error: ModuleNotFoundError: No module named 'no_such_module_for_bt_grasp'" in err
    assert not (tmp_path / "out" / "weigh.jsonl").exists()


def test_run_with_a_bad_plugin_is_exit_2_before_the_simulator(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    tree = tmp_path / "weigh.xml"
    tree.write_text(TREE)
    bad = tmp_path / "bad.py"
    bad.write_text("from bt_grasp.nodes import input_port\nPORT = input_port('x', dict, 'a=1')\n")
    assert main(["run", str(tree), "--scene", str(SCENE), "--leaves", str(bad), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert err.endswith(f"{bad}:2: bad declaration: port 'x': the default 'a=1' is text, but a dict cannot be read "
                        "from text (give it from_port_text, or a default such as '{x}')")


def test_the_resident_process_gets_the_leaves_as_absolute_paths(tmp_path: Path,
                                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    from bt_grasp.episode import EpisodeRequest
    from bt_grasp.resident.client import _absolute
    from bt_grasp.resident.protocol import request_adapter

    monkeypatch.chdir(tmp_path)
    request = _absolute(EpisodeRequest(tree=Path("t.xml"), scene=SCENE, leaves=("my_leaves.py", "my_pkg.nodes")))
    assert request.leaves == (str(tmp_path / "my_leaves.py"), "my_pkg.nodes")
    adapter = request_adapter()
    assert adapter.validate_python(adapter.dump_python(request, mode="json")).leaves == request.leaves
