"""The controller tick by tick with stand-in leaves (tests/control/stand_ins.py describes the 5-tick run):
every command, every breakpoint kind, rejected values, recording and re-applying interventions."""

from __future__ import annotations

import threading
from collections.abc import Mapping
from typing import Any

import pytest

from bt_grasp.control import (
    ChooseObject,
    ClearBreakpoint,
    Command,
    CommandError,
    Controller,
    FireFault,
    InterventionRecord,
    Pause,
    Restart,
    Resume,
    RunState,
    SeedPolicy,
    SetBlackboard,
    SetBreakpoint,
    Source,
    Step,
    Stop,
    command_from_json,
    command_to_json,
    parse_breakpoint,
)
from bt_grasp.errors import InputError
from tests.control.stand_ins import STEP_NS, Stepper, build, run


class Operator:
    """A scripted operator: each time the run pauses it notes the state and sends the next batch."""

    def __init__(self, *batches: list[Command], stepper: Stepper | None = None) -> None:
        self.batches = list(batches)
        self.seen: list[RunState] = []
        self.steps_at_pause: list[int] = []
        self.stepper = stepper
        self.control: Controller | None = None

    def __call__(self, state: RunState) -> None:
        assert self.control is not None
        self.seen.append(state)
        if self.stepper is not None:
            self.steps_at_pause.append(self.stepper.steps)
        for command in self.batches.pop(0) if self.batches else [Resume()]:
            self.control.send(command, Source.TERMINAL)


def controlled(operator: Operator, **kwargs: Any) -> Controller:
    control = Controller(idle=operator, **kwargs)
    operator.control = control
    return control


class Sink:
    def __init__(self) -> None:
        self.records: list[tuple[int, dict[str, Any]]] = []

    def write_intervention(self, stamp_ns: int, record: Mapping[str, Any]) -> None:
        self.records.append((stamp_ns, dict(record)))


class Faults:
    def __init__(self) -> None:
        self.fired: list[tuple[str, dict[str, Any], int]] = []

    def __call__(self, kind: str, params: Mapping[str, Any], tick: int) -> str:
        if kind != "frame_drop":
            raise CommandError(f"unknown fault kind '{kind}'")
        self.fired.append((kind, dict(params), tick))
        return f"{kind} fired"


def attach(control: Controller, height: float = 0.05, **kwargs: Any) -> tuple[Any, Stepper]:
    tree, stepper = build(height)
    control.attach(tree, stepper.now_ns, **kwargs)
    return tree, stepper


def test_an_idle_controller_changes_nothing() -> None:
    plain_tree, plain_stepper = build()
    plain, plain_stream = run(plain_tree, plain_stepper)
    control = Controller()
    tree, stepper = attach(control)
    outcome, stream = run(tree, stepper, control)
    assert (outcome.status, outcome.ticks, outcome.stopped) == (plain.status, plain.ticks, False) == ("SUCCESS", 5,
                                                                                                      False)
    assert stream == plain_stream and stepper.steps == plain_stepper.steps == 4
    assert control.interventions == ()


def test_pause_step_and_resume_tick_by_tick() -> None:
    # paused before tick 1 -> Step(1): tick 1, paused -> Step(2): ticks 2, 3, paused -> Resume: ticks 4, 5 (end)
    operator = Operator([Step(1)], [Step(2)], [Resume()])
    control = controlled(operator, start_paused=True)
    tree, stepper = attach(control)
    operator.stepper = stepper
    outcome, _ = run(tree, stepper, control)
    assert [s.tick for s in operator.seen] == [0, 1, 3]
    assert [s.pause_reason for s in operator.seen] == ["paused before the first tick", "stepped to tick 1",
                                                       "stepped to tick 3"]
    # simulated time stands while paused: the physics steps after the boundary, never during the pause
    assert [round(s.sim_time_s / (STEP_NS * 1e-9)) for s in operator.seen] == [0, 0, 2]
    assert operator.steps_at_pause == [0, 0, 2]
    assert outcome.status == "SUCCESS" and outcome.ticks == 5
    assert control.interventions == ()  # watching is not recorded


def test_a_pause_sent_while_running_holds_at_the_next_boundary() -> None:
    operator = Operator([Pause()], [Resume()])  # Pause while paused changes nothing; Resume lets it go
    control = controlled(operator, breakpoints=[parse_breakpoint("tick:2")])
    tree, stepper = attach(control)
    outcome, _ = run(tree, stepper, control)
    assert [s.tick for s in operator.seen] == [2, 2]
    assert outcome.ticks == 5


def test_stop_ends_the_run_at_its_tick_and_is_recorded() -> None:
    sink = Sink()
    operator = Operator([Stop()])
    control = controlled(operator, breakpoints=[parse_breakpoint("tick:2")])
    tree, stepper = attach(control, sink=sink)
    outcome, _stream = run(tree, stepper, control)
    assert outcome.stopped and outcome.status == "RUNNING" and outcome.ticks == 2
    assert stepper.steps == 1  # stepped after tick 1 only
    assert tree.find("Move").bt_state.value == "IDLE"  # halted: a RUNNING leaf is cancelled
    assert [(stamp, r["tick"], r["kind"], r["source"]) for stamp, r in sink.records] == [
        (STEP_NS, 2, "stop", "terminal")]


def test_restart_stops_and_says_which_seed() -> None:
    operator = Operator([Restart(SeedPolicy.NEXT)])
    control = controlled(operator, breakpoints=[parse_breakpoint("tick:1")])
    tree, stepper = attach(control)
    outcome, _ = run(tree, stepper, control)
    assert outcome.stopped and outcome.ticks == 1 and control.restart is SeedPolicy.NEXT
    assert control.interventions[0].command == {"kind": "restart", "seed": "next"}


@pytest.mark.parametrize(
    ("spec", "paused_at"),
    [
        ("tick:3", [3]),
        ("tick:0", [0]),
        ("time:0.025", [4]),  # after tick t the clock reads (t - 1) * 10 ms: 30 ms >= 25 ms first after tick 4
        ("time:0", [0]),
        ("fail", [1]),  # Check's first attempt fails (FLAKY) within tick 1
        ("fail:FLAKY", [1]),
        ("fail:TOO_LOW", []),  # no such failure in this run
        ("bb:target", [1]),  # See writes target in tick 1 only
        ("bb:height", []),  # nobody writes it
    ],
)
def test_each_breakpoint_kind_pauses_where_it_says(spec: str, paused_at: list[int]) -> None:
    operator = Operator()
    control = controlled(operator, breakpoints=[parse_breakpoint(spec)])
    tree, stepper = attach(control)
    outcome, _ = run(tree, stepper, control)
    assert [s.tick for s in operator.seen] == paused_at
    assert all(spec in s.pause_reason for s in operator.seen)
    assert outcome.status == "SUCCESS" and outcome.ticks == 5


def test_a_failure_breakpoint_shows_the_failure() -> None:
    operator = Operator()
    control = controlled(operator, breakpoints=[parse_breakpoint("fail")])
    tree, stepper = attach(control)
    run(tree, stepper, control)
    failure = operator.seen[0].last_failure
    assert failure is not None and (failure.tick, failure.leaf, failure.reason) == (1, "Check", "FLAKY")


@pytest.mark.parametrize("by_path", [False, True])
def test_a_node_breakpoint_holds_inside_the_tick_before_the_node_starts(by_path: bool) -> None:
    sink = Sink()
    target = build()[0].find("Move").bt_path if by_path else "Move"  # a path is BT.CPP's: Move::5
    # held before Move in tick 1: set the height (applied at the boundary after tick 1, recorded there), resume;
    # Move is RUNNING from then on: no second hold
    operator = Operator([SetBlackboard("height", "0.07"), Resume()])
    control = controlled(operator, breakpoints=[parse_breakpoint(f"node:{target}")])
    tree, stepper = attach(control, sink=sink)
    path = tree.find("Move").bt_path
    outcome, _ = run(tree, stepper, control)
    assert len(operator.seen) == 1
    held = operator.seen[0]
    assert held.pause_reason == f"before {path} (tick 1)" and held.tick == 0
    statuses = {n.name: n.status for n in held.nodes}
    assert statuses["See"] == "SUCCESS" and statuses["Move"] == "IDLE"
    assert [r["tick"] for _, r in sink.records] == [1]
    # Move read height 0.05 when it started in tick 1 (5 ticks), so the edit at the boundary after tick 1 came
    # after it had counted one tick: it finishes when its count reaches round(0.07 * 100) = 7
    assert outcome.ticks == 7


def test_setting_an_entry_converts_it_as_the_ports_do() -> None:
    sink = Sink()
    operator = Operator([SetBlackboard("height", "0.08"), SetBlackboard("mode", "slow"), Resume()])
    control = controlled(operator, start_paused=True)
    tree, stepper = attach(control, sink=sink)
    outcome, _ = run(tree, stepper, control)
    assert outcome.ticks == 8  # Move runs round(0.08 * 100) ticks
    assert tree.root_blackboard.get("height") == 0.08 and tree.root_blackboard.get("mode") == "slow"
    assert [(r["tick"], r["command"]) for _, r in sink.records] == [
        (0, {"kind": "set_blackboard", "key": "height", "value": 0.08}),
        (0, {"kind": "set_blackboard", "key": "mode", "value": "slow"}),
    ]


@pytest.mark.parametrize(
    ("command", "words"),
    [
        (SetBlackboard("height", "high"), ["'height'", "needs a number", "unchanged"]),
        (SetBlackboard("mode", "medium"), ["'mode'", "must be one of fast, slow", "unchanged"]),
        (SetBlackboard("nothing", 3), ["'nothing'", "no port"]),
        (SetBlackboard("_private", 1), ["private"]),
        (ChooseObject(1, "target"), ["holds no detections yet"]),  # before tick 1: nothing seen
    ],
)
def test_a_bad_value_gets_one_sentence_and_the_run_goes_on_untouched(command: Command, words: list[str]) -> None:
    sink = Sink()
    operator = Operator([command, Resume()])
    control = controlled(operator, start_paused=True)
    tree, stepper = attach(control, sink=sink)
    plain_tree, plain_stepper = build()
    _, plain_stream = run(plain_tree, plain_stepper)
    _outcome, stream = run(tree, stepper, control)
    message = control.state().message
    assert all(w in message for w in words), message
    assert "\n" not in message and message.count(". ") == 0
    assert stream == plain_stream and sink.records == []
    assert tree.root_blackboard.get("height") == 0.05 and tree.root_blackboard.get("mode") == "fast"


def test_choosing_an_object_from_the_detections() -> None:
    sink = Sink()
    operator = Operator([ChooseObject(5), ChooseObject("green")], [ChooseObject("blue"), Resume()])
    control = controlled(operator, breakpoints=[parse_breakpoint("tick:1")])
    tree, stepper = attach(control, sink=sink)
    run(tree, stepper, control)
    first = operator.seen[0]
    assert [(d.index, d.label) for d in first.detections] == [(0, "red"), (1, "blue")]
    assert "no detection labelled 'green'" in operator.seen[1].message  # the second refusal is the last message
    assert tree.root_blackboard.get("moved") == "blue"
    assert [r["command"] for _, r in sink.records] == [
        {"kind": "choose_object", "choice": 1, "entry": "target", "detections": "objects"}]


def test_firing_a_fault_calls_the_injector_at_the_boundary() -> None:
    sink, faults = Sink(), Faults()
    operator = Operator([FireFault("frame_drop", {"frames": 2}), FireFault("meteor"), Resume()])
    control = controlled(operator, breakpoints=[parse_breakpoint("tick:2")])
    tree, stepper = attach(control, sink=sink, fire_fault=faults)
    run(tree, stepper, control)
    assert faults.fired == [("frame_drop", {"frames": 2}, 2)]
    assert control.state().message == "unknown fault kind 'meteor'"
    assert [(r["tick"], r["effect"]) for _, r in sink.records] == [(2, "frame_drop fired")]


def test_no_injector_no_fault() -> None:
    operator = Operator([FireFault("frame_drop")])
    control = controlled(operator, start_paused=True)
    tree, stepper = attach(control)
    run(tree, stepper, control)
    assert "no fault injector" in operator.seen[-1].message or "no fault injector" in control.state().message
    assert control.interventions == ()


def test_breakpoints_set_and_cleared_while_running() -> None:
    operator = Operator([SetBreakpoint(parse_breakpoint("tick:3")), SetBreakpoint(parse_breakpoint("tick:4")),
                         Resume()], [ClearBreakpoint(parse_breakpoint("tick:4")), Resume()])
    control = controlled(operator, start_paused=True)
    tree, stepper = attach(control)
    run(tree, stepper, control)
    assert [s.tick for s in operator.seen] == [0, 3]
    assert operator.seen[1].breakpoints == ("tick:3", "tick:4")
    assert control.state().breakpoints == ("tick:3",)


def test_a_node_breakpoint_must_name_a_node() -> None:
    with pytest.raises(InputError, match=r"--break: 'node:Nope' names no node of the tree; nodes: .*Move"):
        attach(Controller([parse_breakpoint("node:Nope")]))
    operator = Operator([SetBreakpoint(parse_breakpoint("node:Nope")), Resume()])
    control = controlled(operator, start_paused=True)
    tree, stepper = attach(control)
    run(tree, stepper, control)
    assert "names no node" in control.state().message and control.state().breakpoints == ()


def test_recorded_interventions_applied_again_give_the_same_run() -> None:
    sink, faults = Sink(), Faults()
    # paused before tick 1: height, resume -> breakpoint after tick 1: choose blue, step 1 -> after tick 2: fire a
    # fault, step 2 -> after tick 4: stop
    operator = Operator([SetBlackboard("height", "0.07"), Resume()], [ChooseObject("blue"), Step(1)],
                        [FireFault("frame_drop", {"frames": 1}), Step(2)], [Stop()])
    control = controlled(operator, start_paused=True, breakpoints=[parse_breakpoint("tick:1")])
    tree, stepper = attach(control, sink=sink, fire_fault=faults)
    outcome, stream = run(tree, stepper, control)
    recorded = [InterventionRecord.from_json(r) for _, r in sink.records]
    assert [(r.tick, r.command["kind"]) for r in recorded] == [
        (0, "set_blackboard"), (1, "choose_object"), (2, "fire_fault"), (4, "stop")]
    assert outcome.stopped and outcome.ticks == 4

    again_sink, again_faults = Sink(), Faults()
    replay = Controller(replay=recorded)
    tree2, stepper2 = attach(replay, sink=again_sink, fire_fault=again_faults)
    outcome2, stream2 = run(tree2, stepper2, replay)
    assert stream2 == stream and (outcome2.ticks, outcome2.stopped) == (4, True)
    assert again_faults.fired == faults.fired
    assert [(r["tick"], r["command"], r["source"]) for _, r in again_sink.records] == [
        (r.tick, r.command, "resim") for r in recorded]
    assert tree2.root_blackboard.get("target").label == "blue"


def test_front_ends_send_from_their_own_thread() -> None:
    control = Controller(start_paused=True)
    tree, stepper = attach(control)
    result: dict[str, Any] = {}
    worker = threading.Thread(target=lambda: result.update(out=run(tree, stepper, control)))
    worker.start()
    try:
        assert control.wait(lambda s: s.paused and s.tick == 0, 10).paused
        control.send(SetBlackboard("height", 0.06), Source.FOXGLOVE)
        control.send(Step(2))
        state = control.wait(lambda s: s.paused and s.tick == 2, 10)
        assert state.tick == 2 and ("height", "0.06") in state.blackboard and not state.finished
        assert state.interventions[0].source == "foxglove"
        assert stepper.steps == 1
        control.send(Resume())
        worker.join(10)
    finally:
        if worker.is_alive():
            control.send(Stop())
            worker.join(10)
    assert result["out"][0].ticks == 6


@pytest.mark.parametrize(
    "command",
    [Pause(), Resume(), Step(3), Stop(), SetBreakpoint(parse_breakpoint("fail:NO_DETECTION")), ClearBreakpoint(),
     ClearBreakpoint(parse_breakpoint("time:1.5")), SetBlackboard("lift_height", 0.2), ChooseObject("red", "object"),
     FireFault("gripper_slip", {"force_n": 2.0}), Restart(SeedPolicy.NEXT)],
)
def test_every_command_has_a_json_form(command: Command) -> None:
    assert command_from_json(command_to_json(command)) == command


@pytest.mark.parametrize(
    ("data", "words"),
    [
        ({"kind": "jump"}, "unknown command kind 'jump'"),
        ([1], "a command is a JSON object"),
        ({"kind": "step", "n": 0}, "at least 1 tick"),
        ({"kind": "step", "n": "2"}, "needs 'n' (int)"),
        ({"kind": "set_blackboard", "key": "a", "value": [1]}, "needs 'value'"),
        ({"kind": "set_breakpoint", "breakpoint": "tick:x"}, "'tick:x': 'x' is not a tick number"),
        ({"kind": "restart", "seed": "other"}, "'same' or 'next'"),
    ],
)
def test_a_malformed_command_is_one_sentence(data: Any, words: str) -> None:
    with pytest.raises(CommandError, match=words.replace("(", r"\(").replace(")", r"\)")):
        command_from_json(data)


@pytest.mark.parametrize(
    ("spec", "problem"),
    [
        ("nodes:X", "unknown kind 'nodes'"),
        ("node:", "'node:' names nothing"),
        ("tick:-1", "a tick is 0 or more"),
        ("tick:two", "'two' is not a tick number"),
        ("time:nan", "a time is a finite number of seconds, 0 or more"),
        ("fail:", "a reason after 'fail:' is empty"),
        ("Perceive", "no kind before ':'"),
    ],
)
def test_a_bad_breakpoint_spec_is_one_sentence(spec: str, problem: str) -> None:
    with pytest.raises(InputError) as info:
        parse_breakpoint(spec)
    assert info.value.message == (f"--break: '{spec}': {problem}; expected node:NAME, fail, fail:REASON, fail:all, "
                                  "bb:KEY, tick:N or time:S")


@pytest.mark.parametrize("spec", ["node:pick/Perceive", "fail", "fail:NO_DETECTION", "fail:all", "bb:object",
                                  "tick:0", "time:2.5"])
def test_a_breakpoint_spec_round_trips(spec: str) -> None:
    assert parse_breakpoint(spec).spec == spec
