"""Issue 42, findings 5, 6 and 9: every path into the controller is one validation (Foxglove parameters and
/control/command messages alike): no NaN or infinity, bounded messages and lists, updates compared with the set
the controller holds (not a stale view), and no file named over control unless it lies under a folder the run's
user named (``--control-files DIR``), in sentences that never quote a file."""

from __future__ import annotations

import json
import math
import threading
import time
from pathlib import Path
from typing import Any

import pytest

from bt_grasp.control import CommandError, Controller, SetBlackboard, command_from_json
from bt_grasp.foxglove.control import COMMAND_TOPIC, FoxgloveControl
from tests.control.stand_ins import build, run


def _attached(**kwargs: Any) -> tuple[Controller, Any]:
    control = Controller(start_paused=True, **kwargs)
    tree, stepper = build()
    control.attach(tree, stepper.now_ns)
    return control, (tree, stepper)


# -- finding 5 ---------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("value", ["NaN", "Infinity", "-Infinity", "1e999"])
def test_finding5_a_command_message_with_nan_or_infinity_is_refused(value: str) -> None:
    """/control/command took NaN and Infinity for set_blackboard (the bb.* parameters refused them); the log
    recorded "nan" as text, so --resim said the interventions differ."""
    control, _ = _attached()
    fox = FoxgloveControl(control)
    answer = fox.command_message(f'{{"kind": "set_blackboard", "key": "height", "value": {value}}}'.encode())
    assert answer.sent == () and len(answer.problems) == 1, answer
    assert "finite" in answer.problems[0] and "\n" not in answer.problems[0], answer.problems[0]


@pytest.mark.parametrize("name", ["run.step", "run.paused", "run.stop", "run.restart", "choose.object", "fault.fire",
                                  "bb.lift_height", "breakpoints"])
@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, 1e308, 10**30])
def test_finding5_every_parameter_refuses_nan_and_infinity_in_one_sentence(name: str, value: float) -> None:
    """Found by the fuzz suite's control surface: `run.step` set to infinity was an OverflowError out of the
    viewer's request (int(inf))."""
    control, _ = _attached()
    answer = FoxgloveControl(control).set_parameters({name: value})
    for command in answer.sent:  # what went through is finite and bounded
        assert all(not isinstance(v, float) or math.isfinite(v) for v in vars(command).values()), command
    assert len(answer.problems) <= 1 and all("\n" not in p for p in answer.problems), answer


def test_finding5_the_one_validation_holds_for_every_way_a_command_is_made() -> None:
    for bad in (math.nan, math.inf, -math.inf):
        with pytest.raises(CommandError, match="finite"):
            SetBlackboard("height", bad)
        with pytest.raises(CommandError, match="finite"):
            command_from_json({"kind": "set_blackboard", "key": "height", "value": bad})
        with pytest.raises(CommandError, match="finite"):
            command_from_json({"kind": "fire_fault", "fault": "frame_drop", "params": {"frames": bad}})
    with pytest.raises(CommandError, match="characters"):
        SetBlackboard("height", "x" * 100_000)


# -- finding 6 ---------------------------------------------------------------------------------------------------
def test_finding6_twenty_thousand_breakpoints_are_refused_at_once() -> None:
    """20,000 breakpoints in one parameter (a 230 KB message) stalled the tick loop about 5 minutes while every
    other command waited."""
    control, _ = _attached()
    fox = FoxgloveControl(control)
    specs = [f"tick:{i}" for i in range(20_000)]
    start = time.monotonic()
    answer = fox.set_parameters({"breakpoints": specs})
    message = fox.command_message(json.dumps({"kind": "set_breakpoint", "breakpoint": "x" * 300_000}).encode())
    assert time.monotonic() - start < 1.0
    assert answer.sent == () and "at most" in answer.problems[0], answer
    assert message.sent == () and len(message.problems) == 1, message


def test_finding6_a_cleared_list_is_compared_with_the_controllers_set_not_a_stale_view() -> None:
    """A later `[]` was compared with a stale view (the one before the first list was applied), found nothing
    to clear, and was lost: the run stopped at tick 1."""
    control, (tree, stepper) = _attached()
    fox = FoxgloveControl(control)
    assert fox.set_parameters({"breakpoints": ["tick:1", "tick:2"]}).problems == ()
    assert fox.set_parameters({"breakpoints": []}).problems == ()  # the view still says: no breakpoints
    assert fox.set_parameters({"run.paused": False}).problems == ()
    out: dict[str, Any] = {}
    thread = threading.Thread(target=lambda: out.update(result=run(tree, stepper, control)), daemon=True)
    thread.start()
    thread.join(20)
    assert not thread.is_alive(), control.state()
    outcome, _stream = out["result"]
    assert outcome.ticks == 5 and control.state().breakpoints == ()


# -- finding 9 ---------------------------------------------------------------------------------------------------
FILE_TREE = """
<root BTCPP_format="4">
  <BehaviorTree ID="T">
    <Sequence><ReadFile file="{calibration_file}"/><AlwaysSuccess/></Sequence>
  </BehaviorTree>
</root>
"""


def _file_controller(control_files: Path | None) -> tuple[Controller, FoxgloveControl]:
    from bt_grasp.clock import ManualClock
    from bt_grasp.nodes import Leaf, Status, action, input_port
    from bt_grasp.tree.builtins import builtin_registry
    from bt_grasp.tree.loader import load_tree_from_string

    registry = builtin_registry()

    @action(ports=[input_port("file", str, "{calibration_file}", "a file")])
    class ReadFile(Leaf):
        def update(self) -> Status:
            return Status.SUCCESS

    registry.register(ReadFile)

    clock = ManualClock()
    tree = load_tree_from_string(FILE_TREE, registry, clock=clock)
    tree.root_blackboard.set("calibration_file", "scenes/tabletop.calibration.yaml")
    control = Controller()
    control.attach(tree, clock.now_ns)
    assert control.between_ticks(0) is False  # the view a viewer sees before the first tick: the tree's settings
    extra = {} if control_files is None else {"control_files": control_files}  # main had no such argument
    return control, FoxgloveControl(control, **extra)


def test_finding9_no_file_can_be_named_over_control_by_default(tmp_path: Path) -> None:
    """With --control on 127.0.0.1 any local user could set bb.calibration_file to a file the run's user can
    read; the refusal quoted its content ('hunter2-SECRET-VALUE') to every viewer and into the log, and told
    whether files exist."""
    secret = tmp_path / "secret.yaml"
    secret.write_text("version: hunter2-SECRET-VALUE\n")
    _control, fox = _file_controller(None)
    answers = [fox.set_parameters({"bb.calibration_file": str(path)}) for path in (secret, tmp_path / "none.yaml")]
    answers.append(fox.command_message(json.dumps(
        {"kind": "set_blackboard", "key": "calibration_file", "value": str(secret)}).encode()))
    for answer in answers:
        assert answer.sent == () and len(answer.problems) == 1, answer
        assert "--control-files" in answer.problems[0] and "hunter2" not in answer.problems[0]
    shown = [a.problems[0].replace("secret.yaml", "X").replace("none.yaml", "X") for a in answers[:2]]
    assert shown[0] == shown[1], "the sentence tells whether the file exists"


def test_finding9_a_file_named_over_control_must_lie_under_the_folder_the_user_named(tmp_path: Path) -> None:
    allowed = tmp_path / "allowed"
    allowed.mkdir()
    (allowed / "cal.yaml").write_text("version: 1\n")
    (tmp_path / "secret.yaml").write_text("version: hunter2-SECRET-VALUE\n")
    (allowed / "link.yaml").symlink_to(tmp_path / "secret.yaml")
    _control, fox = _file_controller(allowed)
    ok = fox.set_parameters({"bb.calibration_file": str(allowed / "cal.yaml")})
    assert ok.problems == () and len(ok.sent) == 1
    for outside in (tmp_path / "secret.yaml", allowed / ".." / "secret.yaml", allowed / "link.yaml",
                    tmp_path / "nothing.yaml", "relative.yaml"):
        answer = fox.set_parameters({"bb.calibration_file": str(outside)})
        assert answer.sent == () and "not under" in answer.problems[0] and "hunter2" not in answer.problems[0], \
            answer
    assert COMMAND_TOPIC  # the same rule for the command topic: test_finding9_no_file_can_be_named_over_control...


def test_finding9_the_calibration_leaf_quotes_nothing_of_the_file_it_reads(tmp_path: Path) -> None:
    """The leaf that reads the file a blackboard entry names (the one a viewer may set) fails in a sentence that
    names the file and the key, never a value or an unknown key of it."""
    from bt_grasp.errors import ConfigError
    from bt_grasp.perception.calibration_file import load_calibration

    for text in ("version: hunter2-SECRET-VALUE\n", "hunter2-SECRET-VALUE: 1\n"):
        secret = tmp_path / "secret.yaml"
        secret.write_text(text)
        with pytest.raises(ConfigError) as caught:
            load_calibration(secret, quote=False)
        assert "hunter2" not in str(caught.value) and str(secret) in str(caught.value)
