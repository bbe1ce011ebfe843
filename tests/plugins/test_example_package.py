"""The example plugin package (examples/bt_grasp_example_leaves) installed with `pip install -e` into a
throwaway venv: bt_grasp finds its nodes through the ``bt_grasp.leaves`` entry point with no flag; its own tests
pass there; and in one real run on the simulator, together with a leaf from a ``--leaves`` file, both users'
failure reasons are matched by FailureIs and show in `replay --failures` and the run report."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
EXAMPLE = REPO / "examples" / "bt_grasp_example_leaves"
USER_FILE = Path(__file__).parent / "data" / "user_nodes.py"
CALIB = REPO / "tests/data/calibration/tabletop_eye_to_hand.yaml"
SCENE = REPO / "scenes/tabletop.yaml"

DRY_TREE = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence>
      <Fallback>
        <GripperOpenAtLeast min_mm="200"/>
        <FailureIs reason="GRIPPER_TOO_NARROW" leaf="GripperOpenAtLeast"/>
      </Fallback>
      <Dwell seconds="0.03"/>
    </Sequence>
  </BehaviorTree>
</root>
"""

# the pick of trees/pick.xml, with a user leaf from a file (CheckWeight: 750 g is too heavy) and one from the
# installed package (GripperOpenAtLeast: the UR5's gripper opens 85 mm, never 200) failing with their own
# reasons, each recovered by FailureIs
SIM_TREE = """<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence name="pick">
      <Fallback>
        <CheckWeight grams="750"/>
        <FailureIs reason="WEIGHT_OUT_OF_RANGE" leaf="CheckWeight"/>
      </Fallback>
      <LoadCalibration file="{calibration_file}"/>
      <OpenGripper/>
      <Fallback>
        <GripperOpenAtLeast min_mm="200"/>
        <Sequence>
          <FailureIs reason="GRIPPER_TOO_NARROW" leaf="GripperOpenAtLeast"/>
          <Dwell seconds="0.2"/>
        </Sequence>
      </Fallback>
      <Perceive color="{color}" target="{target}" objects="{objects}"/>
      <PlanGrasp target="{target}" objects="{objects}" grasp="{grasp}"/>
      <Approach grasp="{grasp}" target="{target}" objects="{objects}"/>
      <Grasp force="40"/>
      <Lift height="{lift_height}"/>
    </Sequence>
  </BehaviorTree>
</root>
"""


def _run(python: Path, *args: str, timeout: float = 600) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(python), *args], capture_output=True, text=True, timeout=timeout, cwd=REPO)


@pytest.fixture(scope="module")
def venv_python(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A throwaway venv that sees .venv's packages (a .pth adds its site-packages) with the example installed
    editable; nothing is installed into .venv itself."""
    venv = tmp_path_factory.mktemp("plugin_venv") / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], check=True, timeout=300)
    python = venv / "bin" / "python"
    site = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          capture_output=True, text=True, check=True).stdout.strip()
    parent = sysconfig.get_paths()["purelib"]
    (Path(site) / "bt_grasp_parent_venv.pth").write_text(f"import site; site.addsitedir({parent!r})\n")
    # --no-deps: bt-grasp comes from .venv; the build backend (setuptools) from pip's configured index
    install = _run(python, "-m", "pip", "install", "--quiet", "--no-deps", "-e", str(EXAMPLE), timeout=600)
    assert install.returncode == 0, install.stdout + install.stderr
    return python


@pytest.mark.slow
def test_the_installed_example_is_found_by_its_entry_point(venv_python: Path, tmp_path: Path) -> None:
    models = _run(venv_python, "-m", "bt_grasp.cli.main", "tree", "models")
    assert models.returncode == 0, models.stderr
    assert '<Condition ID="GripperOpenAtLeast">' in models.stdout and '<Action ID="Dwell">' in models.stdout

    tree = tmp_path / "dry.xml"
    tree.write_text(DRY_TREE)
    # GripperOpenAtLeast needs the robot: a stand-in fails with the plugin's reason; FailureIs matches it,
    # then Dwell (the plugin's own code) waits 30 ms of simulated time: ticks at 0, 10, 20, 30 ms
    dry = _run(venv_python, "-m", "bt_grasp.cli.main", "tree", "run", "--dry", "--json", str(tree),
               "--substitute", "GripperOpenAtLeast=Failure:GRIPPER_TOO_NARROW")
    assert dry.returncode == 0, dry.stdout + dry.stderr
    out = json.loads(dry.stdout)
    assert (out["status"], out["ticks"]) == ("SUCCESS", 4)
    tick_1 = [(move["type"], move["to"]) for move in out["transitions"] if move["tick"] == 1]
    assert ("TestNode", "FAILURE") in tick_1 and ("FailureIs", "SUCCESS") in tick_1  # matched GRIPPER_TOO_NARROW
    assert "failure_reason" not in out["blackboard"]  # the tree succeeded: the recovered failure is cleared

    # the example's own run, alone: not a worker of this run's xdist, and without plugins the machine's Python
    # happens to carry (pytest-benchmark warns, an error under -W error, when it sees xdist)
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTEST_XDIST", "PYTEST_CURRENT"))}
    own_tests = subprocess.run([str(venv_python), "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist",
                                "-p", "no:benchmark", "-W", "error", str(EXAMPLE / "tests")],
                               env=env, capture_output=True, text=True, timeout=300, cwd=EXAMPLE)
    assert own_tests.returncode == 0, own_tests.stdout + own_tests.stderr
    assert "2 passed" in own_tests.stdout

    # .venv itself does not have the plugin: without it the tree names an unknown node
    bare = _run(Path(sys.executable), "-m", "bt_grasp.cli.main", "tree", "validate", str(tree))
    assert bare.returncode == 2 and "unknown node 'GripperOpenAtLeast'" in bare.stderr


@pytest.mark.sim
@pytest.mark.slow
def test_users_leaves_in_a_real_run_replay_and_report(venv_python: Path, tmp_path: Path) -> None:
    tree, log, summary = tmp_path / "weigh_and_pick.xml", tmp_path / "run.mcap", tmp_path / "summary.json"
    tree.write_text(SIM_TREE)
    bt = [str(venv_python), "-m", "bt_grasp.cli.main"]
    run = subprocess.run(
        [*bt, "run", str(tree), "--scene", str(SCENE), "--seed", "3", "--calibration", str(CALIB),
         "--leaves", str(USER_FILE), "--log", str(log), "--summary-json", str(summary), "--quiet"],
        capture_output=True, text=True, timeout=900, cwd=REPO,
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert json.loads(summary.read_text())["success"] is True  # judged by physics: the pick went on

    replay = subprocess.run([*bt, "replay", str(log), "--failures", "--json"], capture_output=True, text=True,
                            timeout=300, cwd=REPO)
    assert replay.returncode == 0, replay.stderr
    failures = [(f["name"], f["reason"]) for f in json.loads(replay.stdout)]
    assert ("CheckWeight", "WEIGHT_OUT_OF_RANGE") in failures
    assert ("GripperOpenAtLeast", "GRIPPER_TOO_NARROW") in failures

    report = tmp_path / "report.html"
    made = subprocess.run([*bt, "replay", str(log), "--report", str(report)], capture_output=True, text=True,
                          timeout=300, cwd=REPO)
    assert made.returncode == 0, made.stderr
    html = report.read_text()
    assert "WEIGHT_OUT_OF_RANGE" in html and "GRIPPER_TOO_NARROW" in html

    # a log never loads code by itself: re-simulating it asks for the --leaves file again
    resim = subprocess.run([*bt, "replay", str(log), "--resim"], capture_output=True, text=True, timeout=300,
                           cwd=REPO)
    assert resim.returncode == 2
    assert resim.stderr.strip() == (f"bt-grasp: error: {log}: the run used --leaves {USER_FILE}; pass them again with "
                                    "--leaves (a log never loads code by itself)")
