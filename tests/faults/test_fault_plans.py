"""The fault plan loader: example plans, the --inject syntax, and bad plans -> one ConfigError with file:line."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from bt_grasp.errors import ConfigError, InputError
from bt_grasp.faults import FaultKind, load_fault_plan

REPO = Path(__file__).resolve().parents[2]
EXAMPLES = sorted((REPO / "faults").glob("*.yaml"))
BAD = REPO / "tests" / "data" / "bad_fault_plans"

# bad plan -> (line the error names, a fragment of the problem)
BAD_PLANS = {
    "unknown_key.yaml": (4, "unknown key 'nht'; did you mean 'nth'?"),
    "bad_kind.yaml": (2, "faults[0].kind"),
    "two_triggers.yaml": (2, "at_tick cannot be combined"),
    "no_trigger.yaml": (2, "needs a trigger"),
    "bad_probability.yaml": (4, "faults[0].probability"),
    "unknown_param.yaml": (6, "unknown key 'frcton'; did you mean 'friction'?"),
    "bad_param_value.yaml": (5, "faults[0].params (planner_fail): calls"),
    "bad_tick.yaml": (3, "faults[0].at_tick"),
    "empty_list.yaml": (1, "at least 1 item"),
    "misspelt_top.yaml": (1, "unknown key 'fault'; did you mean 'faults'?"),
    "zero_nudge.yaml": (7, "faults[1].params (object_nudge): a nudge slides"),
    "nth_without_leaf.yaml": (2, "nth needs on_leaf"),
    "bad_yaml.yaml": (5, "invalid YAML"),
    "zero_offset.yaml": (2, "at least one non-zero component"),
}


def test_every_bad_plan_is_listed() -> None:
    assert sorted(p.name for p in BAD.glob("*.yaml")) == sorted(BAD_PLANS)


@pytest.mark.parametrize("name", sorted(BAD_PLANS))
def test_bad_plan_names_file_and_line(name: str) -> None:
    line, fragment = BAD_PLANS[name]
    with pytest.raises(ConfigError) as info:
        load_fault_plan(BAD / name)
    message = str(info.value)
    assert message.startswith(f"{BAD / name}:{line}: "), message
    assert fragment in message
    assert info.value.exit_code == 2
    assert "\n" not in message  # one sentence


def test_one_example_plan_per_kind() -> None:
    kinds = {load_fault_plan(p).faults[0].kind for p in EXAMPLES}
    assert kinds == set(FaultKind)


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
def test_example_plan_loads(path: Path) -> None:
    plan = load_fault_plan(path)
    assert len(plan) >= 1
    assert plan.source == str(path)
    assert all(f.source == str(path) for f in plan.faults)


def test_plan_defaults_and_round_trip() -> None:
    plan = load_fault_plan(REPO / "faults" / "random_frame_drops.yaml")
    (fault,) = plan.faults
    assert fault.label == "flaky camera"
    assert fault.trigger.probability == 0.3 and fault.trigger.on_leaf == "Perceive" and fault.trigger.nth is None
    assert fault.count == 3
    assert fault.to_dict()["params"] == {"frames": 1}


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("frame_drop@Perceive#1", {"kind": "frame_drop", "trigger": {"on_leaf": "Perceive", "nth": 1}}),
        ("frame_drop@Perceive", {"kind": "frame_drop", "trigger": {"on_leaf": "Perceive", "nth": 1}}),
        ("planner_fail@tick:50", {"kind": "planner_fail", "trigger": {"at_tick": 50}}),
        ("planner_fail@tick:50:calls=2", {"params": {"calls": 2, "within_attempt": False, "status": "no_path"}}),
        ("slip@Lift#1:friction=0.05", {"kind": "gripper_slip", "params": {"friction": 0.05, "force_n": 2.0,
                                                                          "duration_s": 2.0}}),
        ("nudge@Approach#2:dx_m=0.03,dy_m=0,count=2", {"kind": "object_nudge", "count": 2,
                                                       "trigger": {"on_leaf": "Approach", "nth": 2}}),
        ("drop@~0.25", {"kind": "frame_drop", "trigger": {"probability": 0.25}}),
        ("frame_drop@Perceive~0.5", {"trigger": {"on_leaf": "Perceive", "probability": 0.5}}),
        ("ik_fail@PlanGrasp#1:calls=100,within_attempt=true", {"params": {"calls": 100, "within_attempt": True}}),
        ("calib@tick:1:dx_mm=5,name=bumped", {"kind": "calibration_offset", "label": "bumped"}),
        ("timeout@Main/Grasp#1:duration_s=2", {"kind": "leaf_timeout", "trigger": {"on_leaf": "Main/Grasp",
                                                                                     "nth": 1}}),
    ],
)
def test_inject_syntax(text: str, expected: dict[str, object]) -> None:
    (fault,) = load_fault_plan(None, [text]).faults
    as_dict = fault.to_dict()
    for key, value in expected.items():
        assert as_dict[key] == value, (key, as_dict)
    assert fault.source == "--inject" and fault.where == text


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("frame_drop", "missing '@'"),
        ("frame_drop@", "missing '@'"),
        ("@Perceive#1", "missing '@'"),
        ("frame-drop@Perceive", "is not a fault kind"),
        ("foo@Perceive", "kind: Input should be"),
        ("frame_drop@Perceive#x", "cannot read the trigger"),
        ("frame_drop@tick:x", "cannot read the trigger"),
        ("frame_drop@tick:0", "at_tick"),
        ("frame_drop@Perceive~2", "probability"),
        ("slip@Lift:friction=abc", "friction: Input should be a valid number"),
        ("slip@Lift:frictio=0.1", "unknown key 'frictio'; did you mean 'friction'?"),
        ("slip@Lift:friction", "'friction' is not KEY=VALUE"),
        ("slip@Lift:friction=0.1,friction=0.2", "given twice"),
        ("nudge@PlanGrasp:dy_m=0", "a nudge slides"),
        ("frame_drop@Perceive:count=0", "count"),
    ],
)
def test_bad_inject_string(text: str, fragment: str) -> None:
    with pytest.raises(InputError) as info:
        load_fault_plan(None, [text])
    assert info.value.source == "--inject"
    assert not isinstance(info.value, ConfigError) or info.value.source == "--inject"
    assert fragment in info.value.problem, info.value.problem
    assert f"'{text}'" in str(info.value)


def test_file_then_inject_strings_in_order() -> None:
    plan = load_fault_plan(REPO / "faults" / "frame_drop.yaml", ["planner_fail@tick:5", "slip@Lift"])
    assert [f.kind.value for f in plan.faults] == ["frame_drop", "planner_fail", "gripper_slip"]
    assert [f.source for f in plan.faults][1:] == ["--inject", "--inject"]


def test_nothing_to_load_is_an_input_error() -> None:
    with pytest.raises(InputError, match=re.escape("no fault plan file and no --inject")):
        load_fault_plan(None, [])


def test_missing_plan_file() -> None:
    with pytest.raises(ConfigError, match="no such file"):
        load_fault_plan(BAD / "nope.yaml")
